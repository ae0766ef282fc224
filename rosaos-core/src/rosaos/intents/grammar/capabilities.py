"""What a driver can do, said once: the ``capabilities:`` table of its ``intents.yaml``.

Sentence templates list ways of saying things, and whoever wrote them decides what is understood.
Capabilities say what the device can do and what each tool argument *means*; the engine's
compositional reader (:mod:`rosaos.intents.understanding.compose`) does the language work once,
for every driver: verbs, particles, adjectives, quantities with units, vague amounts, group
words. A driver declares::

    capabilities:
      kind: [light, bulb]                  # what people call any device of this driver (singular)
      can:
        - {does: switch_on, tool: turn_on}
        - {does: brightness, tool: set_brightness, args: {brightness: level}}
        - {does: brightness, tool: adjust_brightness, args: {change: change}}
        - {does: colour, tool: set_color_name, args: {name: colour}, values: color}
        - {does: dock, tool: dock, if_described: [dock, charger]}

``does`` is one of :data:`ACTIONS` (``level`` is any other "how much" a device has, a fan's
speed or a blind's height: "up", "down", "to half" reach it as they reach brightness and volume); ``args`` maps each argument of ``tool`` to its meaning
(:data:`MEANINGS`), and ``fixed`` gives arguments passed as written. ``values`` names a list of
the same file whose values the argument takes (a colour the bulb knows). ``if_described`` limits
the capability to instances whose description says one of those words (a ROS robot has a dock
only when it is described with one). ``limits`` gives an argument's range (``{kelvin: [2500,
6500]}``): a value outside it is refused, never clipped. The same ``does`` may appear twice, absolute and relative
(``level`` and ``change``): the engine picks the one the sentence asks for.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

Action = Literal[
    "switch_on",
    "switch_off",
    "toggle",
    "brightness",
    "level",
    "colour",
    "colour_temperature",
    "volume",
    "play",
    "pause",
    "resume",
    "next",
    "previous",
    "shuffle",
    "repeat",
    "repeat_off",
    "move",
    "turn",
    "dock",
    "undock",
    "look",
    "face_front",
    "say",
    "sleep",
    "wake",
]
"""What the core knows how to say, in every language it reads: the verbs that mean each."""
ACTIONS: tuple[str, ...] = Action.__args__  # type: ignore[attr-defined]

Meaning = Literal[
    "level",
    "change",
    "colour",
    "kelvin",
    "kelvin_change",
    "distance",
    "angle",
    "direction",
    "text",
    "query",
    "flag",
]
"""What an argument means, so the engine can fill it from any sentence:

- ``level``: 0-100 percent ("half", "sixty", "75 %"); ``change``: signed percent points, + is up;
- ``colour``: a colour name; ``kelvin``: a colour temperature; ``kelvin_change``: signed kelvin,
  + is cooler;
- ``distance``: signed metres, + is forward; ``angle``: signed degrees, + is to the left
  (counter-clockwise, REP-103); ``direction``: ``left``, ``right``, ``up`` or ``down``;
- ``text``: words to say; ``query``: what to search for; ``flag``: true for "on", false for "off"."""
MEANINGS: tuple[str, ...] = Meaning.__args__  # type: ignore[attr-defined]


class Capability(BaseModel):
    """One thing a driver can do: the tool, and what its arguments mean."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    does: Action
    tool: str = Field(min_length=1)
    args: dict[str, Meaning] = Field(default_factory=dict)
    fixed: dict[str, Any] = Field(default_factory=dict)
    """Arguments passed as written (``{profile: fast}``)."""
    values: str | None = None
    """A list of the same file (``lists:``) whose values the ``colour`` argument takes."""
    if_described: tuple[str, ...] = ()
    """Only instances whose description says one of these words have this capability."""
    limits: dict[str, tuple[float, float]] = Field(default_factory=dict)
    """Argument → the lowest and highest value the tool takes (``{kelvin: [2500, 6500]}``); a
    sentence asking for more is refused by the engine, never clipped."""

    def allows(self, argument: str, value: Any) -> bool:
        """Whether ``value`` is within this capability's limits for ``argument`` (if any)."""
        if argument not in self.limits or not isinstance(value, int | float):
            return True
        low, high = self.limits[argument]
        return low <= value <= high

    @model_validator(mode="after")
    def _one_meaning_each(self) -> Capability:
        meanings = list(self.args.values())
        if len(meanings) != len(set(meanings)):
            raise ValueError(f"{self.tool}: give each meaning to one argument only")
        overlap = set(self.args) & set(self.fixed)
        if overlap:
            raise ValueError(f"{self.tool}: {', '.join(sorted(overlap))} is both in args and fixed; keep one")
        return self

    def argument(self, meaning: str) -> str | None:
        """The name of the argument that takes ``meaning``, or None."""
        return next((name for name, said in self.args.items() if said == meaning), None)


class Capabilities(BaseModel):
    """A driver's ``capabilities:`` table."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    kind: tuple[str, ...] = ()
    """What people call any device of this driver, singular and lowercase ("light", "robot")."""
    can: tuple[Capability, ...] = Field(min_length=1)

    def doing(self, action: str, description: str = "") -> list[Capability]:
        """The capabilities that do ``action`` for an instance described as ``description``."""
        words = description.lower()
        return [
            capability
            for capability in self.can
            if capability.does == action
            and (not capability.if_described or any(word in words for word in capability.if_described))
        ]
