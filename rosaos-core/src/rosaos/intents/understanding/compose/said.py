"""What an action reading is (:class:`Said`), and what the lexicon's rules share.

Split out of :mod:`~rosaos.intents.understanding.compose.actions` so its light and sound words
(:mod:`~rosaos.intents.understanding.compose.level_words`) can build the same readings.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from rosaos.intents.understanding.compose.quantities import Quantity, Size

TURN_VERB = re.compile(r"\b(?:turn|rotate|spin|pivot|swivel|face|twist)\w*\b")

SIZES: dict[str, dict[Size, float]] = {
    "change": {"small": 10, "normal": 20, "large": 40},
    "kelvin_change": {"small": 500, "normal": 700, "large": 1500},
    "distance": {"small": 0.3, "normal": 0.5, "large": 1.0},
    "angle": {"small": 30, "normal": 90, "large": 180},
}


@dataclass(frozen=True)
class Said:
    """One action a clause asks for: what, its values by meaning, and the words left over."""

    action: str
    values: dict[str, Any] = field(default_factory=dict)
    rest: str = ""
    family: str | None = None
    """For ``level``: ``brightness`` or ``volume`` when the words say which; for ``face_front``,
    ``body`` when only the body was meant."""
    quantity: Quantity | None = None
    """The number the values came from, to restate in the reply (:func:`restate`)."""


def cut(text: str, *patterns: re.Pattern[str]) -> str:
    for pattern in patterns:
        text = pattern.sub(" ", text)
    return " ".join(text.split())
