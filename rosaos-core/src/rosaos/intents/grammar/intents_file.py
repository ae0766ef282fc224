"""A driver's ``intents.yaml``: hassil sentence templates, plus which tool each intent calls.

The file is plain hassil format (``language``, ``intents``, ``lists``, ``expansion_rules``,
``skip_words``) with one rosaOS extension: each intent names the MCP tool it calls and the
arguments, in either of two places (both may be used in one file, not for the same intent)::

    language: en
    intents:
      TurnOn:
        tool: turn_on                   # next to ``data:``
        data:
          - sentences: ["turn on [the] light"]
      SetBrightness:
        data:
          - sentences: ["set [the] brightness to {brightness}[%]"]
    lists:
      brightness: {range: {from: 0, to: 100}}
    rosaos:                             # or in one top-level table
      SetBrightness:
        tool: set_brightness
        args: {brightness: "{brightness}"}

An argument value written as ``"{slot}"`` is filled with the matched slot's value. Besides
``{device}``, the engine fills ``{area}`` with the areas of the driver's instances ("it's too dark
in {area}" means the one instance there), and ``every: true`` next to ``tool`` makes an intent
act on every instance ("all the lights to 40%").

A question ("is the turtlebot docked?", "what's playing?") calls a read-only tool, usually
``get_state``, and says what it found, with one of two more keys next to ``tool``::

      IsDocked:
        tool: get_state
        answer:                         # yes/no, from the state the tool returned
          when: {docked: true}
          "yes": "Yes, the {device} is docked."
          "no": "No, the {device} is not docked."
      Battery:
        tool: get_state
        reply: "The {device}'s battery is at {battery:.0%}."

``{device}`` is the device's name; any other ``{key}`` (with an optional format spec) is that key
of the returned state, and ``{result}`` the whole state on one line. hassil
ignores the extra keys; :func:`load_intents_file` strips them anyway, so :attr:`IntentsFile.hassil`
is exactly what :meth:`hassil.Intents.from_dict` accepts. The conformance kit and the offline
local-intent engine both read intents through this one function.

A second, optional extension maps Home Assistant's built-in (multilingual) intents onto the
driver's tools: a top-level ``homeassistant:`` table, described in :mod:`rosaos.intents.grammar.ha_mapping`.

A third, ``capabilities:``, says what the driver can do and what each tool argument means, with
no sentences at all; the engine's compositional reader understands everyday language from it
(:mod:`rosaos.intents.grammar.capabilities`). A file may hold only ``capabilities:`` and no
``intents:``: a new driver needs no templates.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml
from hassil import Intents
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from rosaos.intents.grammar.capabilities import Capabilities
from rosaos.intents.grammar.ha_mapping import HomeAssistantMapping

ROSAOS_KEY = "rosaos"
HOMEASSISTANT_KEY = "homeassistant"
CAPABILITIES_KEY = "capabilities"
ACTION_KEYS = ("tool", "args", "answer", "reply", "every")
DEFAULT_LANGUAGE = "en"
_SLOT_REFERENCE = re.compile(r"^\{(\w+)\}$")


class IntentsFileError(ValueError):
    """An ``intents.yaml`` that cannot be used; the message names the file, the intent and the fix."""


class IntentAnswer(BaseModel):
    """A yes/no question's answer, read from the state the intent's tool returned."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    when: dict[str, Any] = Field(min_length=1)
    """State keys and the values that make the answer "yes"."""
    yes: str = Field(min_length=1)
    no: str = Field(min_length=1)

    @model_validator(mode="before")
    @classmethod
    def _yaml_booleans(cls, data: Any) -> Any:
        # YAML 1.1 reads an unquoted ``yes:``/``no:`` key as a boolean.
        if isinstance(data, dict):
            when = data.get("when")
            if isinstance(when, dict) and any(isinstance(key, bool) for key in when):
                raise ValueError(
                    "a 'when' key reads as true/false: YAML turns an unquoted on, off, yes or no "
                    'into a boolean; quote it: when: {"on": true}'
                )
            return {
                {True: "yes", False: "no"}.get(key, key) if isinstance(key, bool) else key: value
                for key, value in data.items()
            }
        return data


class IntentAction(BaseModel):
    """The tool call an intent stands for, and for a question what to say about its result."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    tool: str = Field(min_length=1)
    """Name of a tool on the driver's MCP server."""
    args: dict[str, Any] = Field(default_factory=dict)
    """Tool arguments; a value ``"{slot}"`` is replaced by the matched slot value."""
    answer: IntentAnswer | None = None
    """For a yes/no question: the answer, from the returned state."""
    reply: str | None = Field(default=None, min_length=1)
    """For a question: the reply, with ``{device}`` and the returned state's ``{key}`` filled in."""
    every: bool = False
    """The template means every instance of the driver ("all the lights"), not one."""

    @model_validator(mode="after")
    def _one_kind_of_reply(self) -> IntentAction:
        if self.answer is not None and self.reply is not None:
            raise ValueError("give 'answer' (a yes/no question) or 'reply', not both")
        return self

    @property
    def is_question(self) -> bool:
        """Whether the intent asks about the device rather than acting on it."""
        return self.answer is not None or self.reply is not None

    def slot_arguments(self) -> dict[str, str]:
        """The arguments filled from slots, as ``{argument: slot name}``."""
        return {
            name: match.group(1)
            for name, value in self.args.items()
            if isinstance(value, str) and (match := _SLOT_REFERENCE.match(value))
        }


class IntentsFile(BaseModel):
    """A parsed, validated ``intents.yaml``."""

    model_config = ConfigDict(frozen=True)

    path: Path
    language: str
    hassil: dict[str, Any]
    """The hassil part of the file, rosaOS keys removed: input for ``hassil.Intents.from_dict``."""
    actions: dict[str, IntentAction]
    """Intent name → the tool call it stands for. Every intent has exactly one."""
    homeassistant: HomeAssistantMapping | None = None
    """How Home Assistant's built-in intents map onto this driver's tools, if it says."""
    capabilities: Capabilities | None = None
    """What the driver can do and what its tools' arguments mean, if it says."""

    def list_values(self, name: str) -> list[str]:
        """The plain output values of the hassil list ``name`` (``lists: {color: {values: ...}}``)."""
        declared = self.hassil.get("lists", {}).get(name, {})
        values = declared.get("values", []) if isinstance(declared, dict) else []
        found = []
        for value in values:
            if isinstance(value, dict):
                value = value.get("out", value.get("in"))
            if isinstance(value, str) and re.fullmatch(r"[\w' -]+", value):
                found.append(value.lower())
        return found

    def intents(self) -> Intents:
        """The hassil :class:`~hassil.Intents` ready for recognition."""
        return Intents.from_dict(self.hassil)


def load_intents_file(path: Path) -> IntentsFile:
    """Read, validate and split a driver's ``intents.yaml``.

    Raises :class:`IntentsFileError` when the file is not YAML, hassil cannot parse it, an intent
    names no tool, or a ``rosaos:`` entry names an intent that does not exist.
    """
    try:
        raw = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as error:
        raise IntentsFileError(f"{path}: cannot read: {error.strerror}") from None
    except yaml.YAMLError as error:
        raise IntentsFileError(f"{path}: not valid YAML: {error}") from None
    if not isinstance(raw, dict):
        raise IntentsFileError(f"{path}: expected a mapping with 'intents:' or 'capabilities:'")
    if raw.get(CAPABILITIES_KEY) is not None and not raw.get("intents"):
        raw = {**raw, "intents": {}}
    elif not isinstance(raw.get("intents"), dict) or not raw["intents"]:
        raise IntentsFileError(
            f"{path}: expected a mapping with a non-empty 'intents:' table (hassil format)"
            " or a 'capabilities:' table"
        )

    own_keys = (ROSAOS_KEY, HOMEASSISTANT_KEY, CAPABILITIES_KEY)
    hassil_dict = {key: value for key, value in raw.items() if key not in own_keys}
    hassil_dict.setdefault("language", DEFAULT_LANGUAGE)
    top_level = raw.get(ROSAOS_KEY) or {}
    if not isinstance(top_level, dict):
        raise IntentsFileError(f"{path}: '{ROSAOS_KEY}:' must map intent names to {{tool, args}}")

    intents: dict[str, Any] = {}
    actions: dict[str, IntentAction] = {}
    for intent_name, intent in raw["intents"].items():
        if not isinstance(intent, dict):
            raise IntentsFileError(f"{path}: intents.{intent_name}: expected a mapping with 'data:'")
        inline = {key: intent[key] for key in ACTION_KEYS if key in intent}
        intents[intent_name] = {key: value for key, value in intent.items() if key not in ACTION_KEYS}
        if inline and intent_name in top_level:
            raise IntentsFileError(
                f"{path}: intents.{intent_name}: tool given both inline and under '{ROSAOS_KEY}:'; keep one"
            )
        declared = inline or top_level.get(intent_name)
        if declared is None:
            raise IntentsFileError(
                f"{path}: intents.{intent_name}: names no tool; add 'tool: <tool name>' next to 'data:'"
            )
        actions[intent_name] = _action(path, intent_name, declared)
    unknown = sorted(set(top_level) - set(intents))
    if unknown:
        raise IntentsFileError(
            f"{path}: {ROSAOS_KEY}: {', '.join(unknown)}: no such intent under 'intents:'; "
            "fix the name or remove the entry"
        )
    hassil_dict["intents"] = intents

    try:
        Intents.from_dict(hassil_dict)
    except Exception as error:  # hassil raises KeyError/TypeError/its own parse errors alike
        raise IntentsFileError(f"{path}: hassil cannot parse it: {type(error).__name__}: {error}") from None
    return IntentsFile(
        path=path,
        language=str(hassil_dict["language"]),
        hassil=hassil_dict,
        actions=actions,
        homeassistant=_homeassistant(path, raw.get(HOMEASSISTANT_KEY)),
        capabilities=_capabilities(path, raw.get(CAPABILITIES_KEY)),
    )


def _capabilities(path: Path, declared: object) -> Capabilities | None:
    if declared is None:
        return None
    try:
        return Capabilities.model_validate(declared)
    except ValidationError as error:
        raise IntentsFileError(f"{path}: {CAPABILITIES_KEY}: {_problems(error)}") from None


def _problems(error: ValidationError) -> str:
    return "; ".join(
        f"{'.'.join(str(part) for part in problem['loc']) or 'value'}: {problem['msg']}"
        for problem in error.errors()
    )


def _homeassistant(path: Path, declared: object) -> HomeAssistantMapping | None:
    if declared is None:
        return None
    try:
        return HomeAssistantMapping.model_validate(declared)
    except ValidationError as error:
        problems = "; ".join(
            f"{'.'.join(str(part) for part in problem['loc']) or 'value'}: {problem['msg']}"
            for problem in error.errors()
        )
        raise IntentsFileError(f"{path}: {HOMEASSISTANT_KEY}: {problems}") from None


def _action(path: Path, intent_name: str, declared: object) -> IntentAction:
    try:
        return IntentAction.model_validate(declared)
    except ValidationError as error:
        problems = "; ".join(
            f"{'.'.join(str(part) for part in problem['loc']) or 'value'}: {problem['msg']}"
            for problem in error.errors()
        )
        raise IntentsFileError(f"{path}: intents.{intent_name}: {problems}") from None
