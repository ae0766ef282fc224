"""Named colours for ``set_color_name``: a colour is a hue and saturation, a white is a kelvin.

The names are the ones people say to a light. The same names make up the ``color`` list in
``intents.yaml`` (a test keeps the two in step).
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass


@dataclass(frozen=True)
class Color:
    """A colour proper, shown by the RGB LEDs: ``hue`` in degrees, ``saturation`` in percent."""

    hue: int
    saturation: int = 100


@dataclass(frozen=True)
class White:
    """A white, shown by the white LEDs at a colour temperature in kelvin."""

    kelvin: int


NamedColor = Color | White

NAMED_COLORS: dict[str, NamedColor] = {
    "red": Color(0),
    "orange": Color(30),
    "amber": Color(45),
    "yellow": Color(60),
    "lime": Color(90),
    "green": Color(120),
    "teal": Color(170),
    "cyan": Color(180),
    "sky blue": Color(200, 70),
    "blue": Color(240),
    "indigo": Color(260),
    "purple": Color(280),
    "violet": Color(290, 60),
    "magenta": Color(300),
    "pink": Color(330, 60),
    # more names people say; each a hue of its own family, never a different colour
    "turquoise": Color(175, 80),
    "aqua": Color(185, 80),
    "navy": Color(235),
    "navy blue": Color(235),
    "royal blue": Color(225),
    "lavender": Color(270, 35),
    "lilac": Color(285, 40),
    "fuchsia": Color(310),
    "hot pink": Color(330, 85),
    "crimson": Color(348),
    "scarlet": Color(5),
    "coral": Color(16, 70),
    "gold": Color(50),
    "mint": Color(150, 45),
    "emerald": Color(140),
    "white": White(4000),
    "warm white": White(2700),
    "soft white": White(3000),
    "candlelight": White(2500),
    "cool white": White(5000),
    "daylight": White(6500),
}


def normalize_color_name(name: str) -> str:
    """Lower-case, with ``-``/``_`` as spaces and single spaces: ``"Warm-White "`` → ``"warm white"``."""
    return " ".join(name.replace("-", " ").replace("_", " ").lower().split())


class UnknownColorError(ValueError):
    """A colour name not in :data:`NAMED_COLORS`; the message suggests the closest names."""


def lookup_color(name: str) -> NamedColor:
    """The colour called ``name`` (case and spacing do not matter), or :class:`UnknownColorError`."""
    key = normalize_color_name(name)
    if key in NAMED_COLORS:
        return NAMED_COLORS[key]
    close = difflib.get_close_matches(key, NAMED_COLORS, n=3, cutoff=0.6)
    hint = f"did you mean {' or '.join(repr(c) for c in close)}? " if close else ""
    raise UnknownColorError(
        f"unknown colour {name!r}; {hint}known colours: {', '.join(NAMED_COLORS)}. "
        "For any other colour use set_color with a hue (0-360) and saturation (0-100)."
    )
