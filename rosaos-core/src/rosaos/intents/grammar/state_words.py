"""A device's state in words a person can hear: what the kernel says to "where is the robot?".

Both engines use it: the ``device_state`` kernel tool returns these sentences next to the raw
state, so an LLM relays "1.4 m ahead of its dock, facing left" instead of radians, and the
offline engine answers questions from the same words.

It reads the ``get_state`` keys the built-in drivers share, and says nothing of keys it does not
know (the raw state is still there for an LLM):

- a robot: ``x``, ``y`` (metres, odometry frame), ``yaw`` (radians), ``linear``, ``angular``,
  and when it has a dock ``docked``; ``battery`` (a fraction, or a percentage above 1);
  ``people_seen`` (``[{x, y, at}]``);
- a light: ``on``, ``brightness`` (percent), ``hue`` (degrees) and ``saturation`` (percent) in
  colour mode, ``color_temp`` (kelvin; 0 in colour mode);
- music: ``is_playing``, ``track``, ``artist``, ``volume``;
- speech: ``speaking``.

Positions are relative to where the odometry starts, with the start heading as "ahead". A
robot that has a dock (its state has ``docked``) starts its odometry there, as a TurtleBot and
the simulator do, so that point is called "its dock"; others call it "where it started".
"""

from __future__ import annotations

import math
from datetime import UTC, datetime
from typing import Any

NEAR = 0.1
"""Metres from the origin that still count as "at" it."""
MOVING_LINEAR = 0.01
MOVING_ANGULAR = 0.02


def doing(state: dict[str, Any] | None) -> str | None:
    """What the device is busy with, read from its state: "moving", "speaking", "playing", or None."""
    if not state:
        return None
    if (
        abs(_number(state.get("linear"))) > MOVING_LINEAR
        or abs(_number(state.get("angular"))) > MOVING_ANGULAR
    ):
        return "moving"
    if state.get("moving"):
        return "moving"
    if state.get("speaking") is True:
        return "speaking"
    if state.get("is_playing") is True:
        return "playing"
    return None


def position(state: dict[str, Any]) -> str | None:
    """Where a robot is, in words and degrees ("1.4 m ahead of its dock, facing left"); None
    when its state has no pose."""
    if state.get("docked") is True:
        return "at its dock"
    if not isinstance(state.get("x"), int | float) or not isinstance(state.get("y"), int | float):
        return None
    origin = "its dock" if "docked" in state else "where it started"
    x, y = float(state["x"]), float(state["y"])
    facing = _facing(state.get("yaw"))
    if math.hypot(x, y) < NEAR:
        where = origin if origin == "where it started" else "by its dock, not docked"
        return f"{where}, {facing}" if facing else where
    parts = []
    if abs(x) >= NEAR:
        parts.append(f"{_metres(abs(x))} {'ahead' if x > 0 else 'behind'}")
    if abs(y) >= NEAR:
        parts.append(f"{_metres(abs(y))} to the {'left' if y > 0 else 'right'}")
    joined = " and ".join(parts)
    where = f"{joined} of {origin}"
    return f"{where}, {facing}" if facing else where


def battery(state: dict[str, Any]) -> str | None:
    """The battery as a percentage ("91%"), or None when the state has none."""
    value = state.get("battery")
    if not isinstance(value, int | float) or isinstance(value, bool):
        return None
    percent = value * 100 if value <= 1 else value
    return f"{percent:.0f}%"


def people_seen(state: dict[str, Any], now: datetime | None = None) -> str:
    """What the robot has seen of people so far, in one clause."""
    seen = state.get("people_seen") or []
    if not seen:
        return "it has not seen anyone so far"
    count = len(seen)
    last = seen[-1]
    ago = ""
    if isinstance(last, dict) and isinstance(last.get("at"), str):
        try:
            at = datetime.fromisoformat(last["at"])
        except ValueError:
            at = None
        if at is not None:
            seconds = ((now or datetime.now(UTC)) - at).total_seconds()
            ago = f", last {_ago(seconds)}"
    sightings = "a sighting" if count == 1 else f"{count} sightings"
    return f"it has seen someone ({sightings}{ago})"


def called(name: str, driver: str = "") -> str:
    """How a reply names a device: "the kitchen light", but "Spotify" for an instance named after
    its driver (a product's name is a proper name: "playing on Spotify", not "on the spotify")."""
    spoken = name.replace("_", " ")
    if driver and spoken.lower() == driver.replace("_", " ").lower():
        return spoken[:1].upper() + spoken[1:]
    return f"the {spoken}"


def describe(name: str, state: dict[str, Any], driver: str = "") -> list[str]:
    """Short sentences about ``state``, one per thing a person might ask; [] when none apply.
    ``driver`` tells a product's name from a common noun (:func:`called`)."""
    the = called(name, driver)
    subject = the[:1].upper() + the[1:]
    said = []
    if isinstance(state.get("on"), bool):
        level = f", at {state['brightness']}% brightness" if state["on"] and "brightness" in state else ""
        said.append(f"{subject} is {'on' if state['on'] else 'off'}{level}.")
    if isinstance(state.get("is_playing"), bool):
        if state["is_playing"] and state.get("track"):
            by = f" by {state['artist']}" if state.get("artist") else ""
            said.append(f"Playing {state['track']}{by} on {the}.")
        else:
            said.append(f"Nothing is playing on {the}.")
        if "volume" in state:
            said.append(f"{subject}'s volume is at {state['volume']}%.")
    where = position(state)
    if where is not None:
        moving = " and moving" if doing(state) == "moving" else ""
        said.append(f"{subject} is {where}{moving}.")
    charge = battery(state)
    if charge is not None:
        said.append(f"{subject}'s battery is at {charge}.")
    if "people_seen" in state:
        said.append(f"{subject}: {people_seen(state)}.")
    if state.get("speaking") is True:
        said.append(f"{subject} is speaking.")
    return said


def _facing(yaw: Any) -> str | None:
    if not isinstance(yaw, int | float) or isinstance(yaw, bool):
        return None
    degrees = math.degrees(float(yaw))
    degrees = (degrees + 180) % 360 - 180
    size = abs(degrees)
    if size < 10:
        return "facing ahead"
    if size > 170:
        return "facing back"
    side = "left" if degrees > 0 else "right"
    if 80 <= size <= 100:
        return f"facing {side}"
    return f"facing {size:.0f}° to the {side}"


def _metres(value: float) -> str:
    return f"{value:.1f} m" if value < 10 else f"{value:.0f} m"


def _ago(seconds: float) -> str:
    if seconds < 90:
        return f"{max(0, round(seconds))} s ago"
    if seconds < 5400:
        return f"{round(seconds / 60)} min ago"
    return f"{round(seconds / 3600)} h ago"


def _number(value: Any) -> float:
    return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else 0.0


_HUES = (
    (15, "red"), (40, "orange"), (52, "amber"), (75, "yellow"), (105, "lime"), (150, "green"),
    (175, "teal"), (195, "cyan"), (225, "sky blue"), (250, "blue"), (270, "indigo"), (285, "purple"),
    (295, "violet"), (315, "magenta"), (345, "pink"), (361, "red"),
)  # fmt: skip
"""The colour a hue is called, by the upper end of its range in degrees."""


def colour(state: dict[str, Any]) -> str | None:
    """A light's colour in words ("blue", "warm white (2700 K)"); None when its state has none."""
    kelvin = state.get("color_temp")
    hue, saturation = state.get("hue"), state.get("saturation")
    if isinstance(kelvin, int | float) and kelvin > 0:
        shade = "warm white" if kelvin < 3300 else "neutral white" if kelvin < 4800 else "cool white"
        return f"{shade} ({round(kelvin)} K)"
    if isinstance(hue, int | float) and isinstance(saturation, int | float):
        if saturation < 15:
            return "white"
        name = next(name for upper, name in _HUES if hue % 360 < upper)
        return f"{'pale ' if saturation < 50 else ''}{name}"
    return None
