"""Device cards: how a driver asks the web page to draw its state, declared in the plugin.

A driver's :class:`~rosaos.drivers.DriverSpec` may carry a :class:`Card`, a short list of
widgets, each naming the ``get_state`` keys it reads. The kernel hands the card to the page with
the device (``GET /devices``, key ``card``); the page draws the widgets, and keeps every key under
a "Details" toggle as raw state. A driver without a card gets a plain list of its state keys.

Widgets (build them with the functions below)::

    Card.of(
        swatch(),                            # a lamp: on, brightness, hue, saturation, color_temp
        gauge("volume", label="Volume", unit="%"),
        text("track", label="Track"),
        flag("is_playing", label="Playing", on_text="playing", off_text="paused"),
        pose(),                              # a mobile robot on the floor map: x, y, yaw
        head(),                              # a robot head: head pose, antennas, body_yaw
        image(),                             # the last camera frame of this device
        controls=[toggle("Power", on_tool="turn_on", off_tool="turn_off", key="on")],
        noun="lamp",                         # the subtitle says "simulated lamp"
    )

Controls (:mod:`rosaos.card_controls`) are tool calls a person makes from the card; each runs as a
one-step process, so it is leased, logged and refused while the emergency stop is latched.

Each compound widget maps its roles to state keys, with defaults that match the built-in drivers;
pass ``keys={"brightness": "level"}`` to read another key. A key missing from the state is drawn
as unknown, never as an error: a card must not break on a driver that leaves a key out.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from rosaos.card_controls import CardControl

WidgetKind = Literal["swatch", "pose", "gauge", "image", "text", "flag", "head"]

ROLES: dict[str, dict[str, str]] = {
    "swatch": {
        "on": "on",
        "brightness": "brightness",
        "hue": "hue",
        "saturation": "saturation",
        "color_temp": "color_temp",
    },
    "pose": {
        "x": "x",
        "y": "y",
        "yaw": "yaw",
        "docked": "docked",
        "battery": "battery",
        "people": "people_seen",
    },
    "head": {
        "head": "head",
        "antennas": "antennas",
        "body_yaw": "body_yaw",
        "said": "last_spoken",
        "awake": "awake",
    },
}
"""The roles of each compound widget and the state key each reads by default."""
REQUIRED_ROLES = {"swatch": ("on",), "pose": ("x", "y"), "head": ("head",)}
"""Roles a state must have for the widget to mean anything; the others may come and go
(``people_seen`` after a detection, ``battery`` on robots that report one)."""
SINGLE_KEY = {"gauge", "text", "flag"}
"""Widgets that show one state key, named by ``key``."""


class CardWidget(BaseModel):
    """One widget of a card: what to draw, and which state keys it reads."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    kind: WidgetKind
    key: str | None = Field(default=None, description="The state key of a gauge, text or flag.")
    label: str | None = Field(
        default=None, max_length=60, description="Shown before the value; default: the key."
    )
    keys: dict[str, str] = Field(default_factory=dict, description="Role -> state key, for swatch/pose/head.")
    unit: str = Field(default="", max_length=12)
    min: float = 0.0
    max: float = 100.0
    on_text: str = "yes"
    off_text: str = "no"

    @model_validator(mode="after")
    def _check(self) -> CardWidget:
        if self.kind in SINGLE_KEY and not self.key:
            raise ValueError(f"a {self.kind} widget needs key=<state key>")
        if self.kind == "gauge" and self.max <= self.min:
            raise ValueError(f"gauge {self.key!r}: max ({self.max}) must be above min ({self.min})")
        unknown = set(self.keys) - set(ROLES.get(self.kind, {}))
        if unknown:
            allowed = ", ".join(ROLES.get(self.kind, {})) or "none"
            raise ValueError(
                f"a {self.kind} widget has no role {', '.join(sorted(unknown))} (roles: {allowed})"
            )
        return self

    def resolved(self) -> dict[str, Any]:
        """The widget as the page gets it: every role mapped to a state key."""
        data = self.model_dump(exclude_none=True)
        if self.kind in ROLES:
            data["keys"] = {**ROLES[self.kind], **self.keys}
        return data


class Card(BaseModel):
    """A driver's card: its widgets, top to bottom, then its controls."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    widgets: list[CardWidget] = Field(min_length=1, max_length=12)
    controls: list[CardControl] = Field(default_factory=list, max_length=12)
    """Buttons, a toggle, sliders...: each a tool call through a process (:mod:`rosaos.card_controls`)."""
    noun: str | None = Field(default=None, max_length=30)
    """What the device is, in a person's words ("lamp", "speaker"): the card's subtitle says
    "simulated lamp" rather than the driver's name."""

    @classmethod
    def of(
        cls, *widgets: CardWidget, controls: list[CardControl] | None = None, noun: str | None = None
    ) -> Card:
        """``Card.of(swatch(), text("mode"), controls=[button("Stop", "stop")], noun="lamp")``."""
        return cls(widgets=list(widgets), controls=controls or [], noun=noun)

    def view(self) -> dict[str, Any]:
        """The JSON the page receives under the device's ``card`` key."""
        return {
            "widgets": [widget.resolved() for widget in self.widgets],
            "controls": [control.model_dump() for control in self.controls],
            "noun": self.noun,
        }


def swatch(keys: dict[str, str] | None = None) -> CardWidget:
    """A light's colour and brightness, with the colour's name as text."""
    return CardWidget(kind="swatch", keys=keys or {})


def pose(keys: dict[str, str] | None = None) -> CardWidget:
    """A mobile robot's position and heading (metres, radians); also puts it on the floor map."""
    return CardWidget(kind="pose", keys=keys or {})


def head(keys: dict[str, str] | None = None) -> CardWidget:
    """A drawing of a head (``{roll, pitch, yaw}`` in degrees), its antennas, and what it last said."""
    return CardWidget(kind="head", keys=keys or {})


def gauge(
    key: str, *, label: str | None = None, unit: str = "", min: float = 0.0, max: float = 100.0
) -> CardWidget:
    """A number drawn as a bar between ``min`` and ``max``."""
    return CardWidget(kind="gauge", key=key, label=label, unit=unit, min=min, max=max)


def text(key: str, *, label: str | None = None, unit: str = "") -> CardWidget:
    """A value as text."""
    return CardWidget(kind="text", key=key, label=label, unit=unit)


def flag(key: str, *, label: str | None = None, on_text: str = "yes", off_text: str = "no") -> CardWidget:
    """A true/false value in words, e.g. ``playing`` / ``paused``."""
    return CardWidget(kind="flag", key=key, label=label, on_text=on_text, off_text=off_text)


def image() -> CardWidget:
    """The last frame this device's camera saved, with the people or faces found in it outlined."""
    return CardWidget(kind="image")


def card_keys_missing(card: Card, state: Mapping[str, Any]) -> list[str]:
    """The state keys ``card`` needs that ``state`` lacks (the conformance kit's check)."""
    missing = []
    for widget in card.widgets:
        if widget.key is not None and widget.key not in state:
            missing.append(widget.key)
        roles = widget.resolved().get("keys", {})
        missing += [roles[role] for role in REQUIRED_ROLES.get(widget.kind, ()) if roles[role] not in state]
    # A control's current value (a switch's on/off, a slider's level) must be readable too.
    missing += [c.key for c in card.controls if c.key is not None and not c.shown_when and c.key not in state]
    return list(dict.fromkeys(missing))
