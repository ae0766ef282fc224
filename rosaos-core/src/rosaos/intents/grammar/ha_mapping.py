"""How a driver maps Home Assistant's built-in intents onto its own tools.

Home Assistant ships sentence templates for dozens of languages (the ``home-assistant-intents``
package): "turn on the kitchen light", "allume la lumière de la cuisine", "set the volume to 70".
A driver opts in with a top-level ``homeassistant:`` table in its ``intents.yaml``::

    homeassistant:
      domain: light                  # the HA domain its devices behave like
      intents:
        HassTurnOn: {tool: turn_on}
        HassLightSet:                # a list: every action whose slots were all heard runs
          - {tool: set_brightness, args: {brightness: "{brightness}"}}
          - {tool: set_color_name, args: {name: "{color}"}}
        HassSetVolumeRelative:
          - {tool: adjust_volume, args: {change: 10}, when: {volume_step: up}}
          - {tool: adjust_volume, args: {change: -10}, when: {volume_step: down}}
        HassGetState:                # questions: which get_state keys mean each HA state
          tool: get_state
          states: {"on": {"on": true}, "off": {"on": false}}

As in the driver's own intents, an argument ``"{slot}"`` takes the matched slot's value. An action
runs only when every slot its arguments name was heard and every ``when`` slot has the given
value, so one HA intent can fan out to the right tool ("red" → colour, "20%" → brightness).
Quote ``"on"``/``"off"`` keys: YAML reads a bare ``on`` as ``true``.
"""

from __future__ import annotations

import re
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, model_validator

HA_INTENT_NAME = re.compile(r"^Hass[A-Z]\w*$")
_SLOT_REFERENCE = re.compile(r"^\{(\w+)\}$")


class HaAction(BaseModel):
    """One tool call an HA intent stands for, and when it applies."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    tool: str = Field(min_length=1)
    args: dict[str, Any] = Field(default_factory=dict)
    """Tool arguments; a value ``"{slot}"`` is replaced by the matched slot value."""
    when: dict[str, Any] = Field(default_factory=dict)
    """Slot values that must have been matched for this action to run (``{volume_step: up}``)."""

    def applies(self, slots: dict[str, Any]) -> bool:
        """Whether every slot this action reads was heard, with the values ``when`` asks for."""
        needed = {match.group(1) for value in self.args.values() if (match := _slot_reference(value))}
        if not needed <= slots.keys():
            return False
        return all(str(slots.get(slot)) == str(value) for slot, value in self.when.items())

    def fill(self, slots: dict[str, Any]) -> dict[str, Any]:
        """The tool arguments with every ``"{slot}"`` replaced by its value."""
        return {
            name: slots[match.group(1)] if (match := _slot_reference(value)) else value
            for name, value in self.args.items()
        }


class HaIntentMapping(BaseModel):
    """What one HA intent does on this driver's devices."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    actions: list[HaAction] = Field(min_length=1)
    states: dict[str, dict[str, Any]] = Field(default_factory=dict)
    """For ``HassGetState``: HA state value (``on``) → the ``get_state`` keys that mean it."""

    @model_validator(mode="before")
    @classmethod
    def _one_or_many(cls, value: Any) -> Any:
        # Written as one action ({tool, args, states}) or a list of actions; stored as a list.
        if isinstance(value, list):
            return {"actions": value}
        if isinstance(value, dict) and "tool" in value:
            states = value.get("states", {})
            return {"actions": [{k: v for k, v in value.items() if k != "states"}], "states": states}
        return value


class HomeAssistantMapping(BaseModel):
    """The ``homeassistant:`` table of an ``intents.yaml``."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    domain: str = Field(pattern=r"^[a-z_]+$")
    """The HA domain the driver's devices behave like: ``light``, ``media_player``, ``switch``..."""
    intents: dict[str, HaIntentMapping] = Field(min_length=1)

    @model_validator(mode="after")
    def _known_names(self) -> HomeAssistantMapping:
        wrong = [name for name in self.intents if not HA_INTENT_NAME.match(name)]
        if wrong:
            raise ValueError(
                f"{', '.join(wrong)}: not Home Assistant intent names (HassTurnOn, HassLightSet...)"
            )
        return self


def _slot_reference(value: Any) -> re.Match[str] | None:
    return _SLOT_REFERENCE.match(value) if isinstance(value, str) else None
