"""Pure checks on a device server's tool listing and results, used by the conformance kit.

Each check returns the problems it found as readable lines (empty means conformant), so a failing
test lists every offending tool at once instead of stopping at the first.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import jsonschema  # type: ignore[import-untyped]  # (no stubs are installed; two calls used)
import mcp_types

from rosaos.card_controls import CardControl

TYPING_KEYS = ("type", "anyOf", "oneOf", "allOf", "enum", "const", "$ref")
"""A JSON-schema property with none of these keys accepts anything: the model cannot know what to send."""

REQUIRED_HINTS = {"read_only_hint": "readOnlyHint", "destructive_hint": "destructiveHint"}


@dataclass(frozen=True)
class OutOfRangeCall:
    """A tool call with an argument past its bound, and the argument names its error should mention."""

    tool: str
    args: dict[str, Any]
    named: tuple[str, ...]


def missing_descriptions(tools: Iterable[mcp_types.Tool]) -> list[str]:
    """Tools without a description (the docstring the model reads to pick a tool)."""
    return [
        f"{tool.name}: no description; write a docstring"
        for tool in tools
        if not (tool.description or "").strip()
    ]


def untyped_arguments(tools: Iterable[mcp_types.Tool]) -> list[str]:
    """Tool arguments whose JSON schema gives no type (``Any``, ``**kwargs``, a bare ``dict``)."""
    problems = []
    for tool in tools:
        schema = tool.input_schema
        if schema.get("type") != "object":
            problems.append(f"{tool.name}: input schema is not an object schema")
            continue
        for name, prop in (schema.get("properties") or {}).items():
            if not isinstance(prop, dict) or not any(key in prop for key in TYPING_KEYS):
                problems.append(
                    f"{tool.name}({name}): untyped argument; annotate it (e.g. int, Literal[...])"
                )
    return problems


def missing_annotations(tools: Iterable[mcp_types.Tool]) -> list[str]:
    """Tools that leave ``readOnlyHint`` or ``destructiveHint`` unset (clients then assume the worst)."""
    problems = []
    for tool in tools:
        for attribute, hint in REQUIRED_HINTS.items():
            if tool.annotations is None or getattr(tool.annotations, attribute) is None:
                problems.append(f"{tool.name}: {hint} not set; pass annotations={{'{hint}': ...}} to @tool")
    return problems


def out_of_range_candidates(tools: Iterable[mcp_types.Tool]) -> list[OutOfRangeCall]:
    """Calls that put one numeric argument just above its ``maximum``, other required ones valid.

    Tools with fewer required arguments come first, so the error is about the bound alone.
    """
    calls: list[tuple[int, OutOfRangeCall]] = []
    for tool in tools:
        properties: dict[str, Any] = tool.input_schema.get("properties") or {}
        required = list(tool.input_schema.get("required") or [])
        for name, prop in properties.items():
            too_big = _just_above_maximum(prop)
            if too_big is None:
                continue
            args = {name: too_big}
            for other in required:
                if other == name:
                    continue
                value = example_value(properties.get(other, {}))
                if value is None:
                    break
                args[other] = value
            else:
                calls.append((len(required), OutOfRangeCall(tool.name, args, (name,))))
    return [call for _, call in sorted(calls, key=lambda item: item[0])]


ODD_NUMBERS = (math.nan, math.inf, -math.inf, 0.0, 1e-9)
"""What a careless or hostile caller sends for a number: not finite, zero, vanishingly small."""


@dataclass(frozen=True)
class OddNumberCall:
    """A tool call with one number set to an odd value; ``must_refuse`` when the schema excludes it."""

    tool: str
    args: dict[str, Any]
    name: str
    value: float
    must_refuse: bool


def odd_number_calls(tools: Iterable[mcp_types.Tool]) -> list[OddNumberCall]:
    """For every number of every tool (optional ones too), a call with each of :data:`ODD_NUMBERS`.

    Not finite is always to be refused. Zero and 1e-9 are to be refused when the schema's bounds
    exclude them; when they allow them, the call must still come back (a speed of 1e-9 that makes
    a move last for ever is a bound missing)."""
    calls = []
    for tool in tools:
        properties: dict[str, Any] = tool.input_schema.get("properties") or {}
        required = list(tool.input_schema.get("required") or [])
        for name, prop in properties.items():
            number = _number_schema(prop)
            if number is None:
                continue
            others: dict[str, Any] = {}
            for other in required:
                if other != name and (value := example_value(properties.get(other, {}))) is not None:
                    others[other] = value
            if len(others) < len([other for other in required if other != name]):
                continue  # the kit cannot make up a valid value for another required argument
            for odd in ODD_NUMBERS:
                refuse = not math.isfinite(odd) or not _within(number, odd)
                calls.append(OddNumberCall(tool.name, {**others, name: odd}, name, odd, refuse))
    return calls


def _number_schema(prop: Any) -> dict[str, Any] | None:
    """The numeric schema of a property (``number``/``integer``, or one branch of an ``anyOf``)."""
    if not isinstance(prop, dict):
        return None
    if prop.get("type") in ("number", "integer"):
        return prop
    for branch in prop.get("anyOf") or []:
        if isinstance(branch, dict) and branch.get("type") in ("number", "integer"):
            return branch
    return None


def _within(schema: dict[str, Any], value: float) -> bool:
    if schema.get("type") == "integer" and value != int(value):
        return False
    checks = (
        ("minimum", lambda bound: value >= bound),
        ("exclusiveMinimum", lambda bound: value > bound),
        ("maximum", lambda bound: value <= bound),
        ("exclusiveMaximum", lambda bound: value < bound),
    )
    return all(check(schema[key]) for key, check in checks if key in schema)


def _just_above_maximum(prop: Any) -> int | float | None:
    if not isinstance(prop, dict) or prop.get("type") not in ("integer", "number"):
        return None
    step = 1 if prop["type"] == "integer" else 0.5
    if "maximum" in prop:
        return prop["maximum"] + step
    if "exclusiveMaximum" in prop:
        return prop["exclusiveMaximum"]
    return None


def example_value(prop: dict[str, Any]) -> Any:
    """A valid value for a simple JSON-schema property, or None when the kit cannot make one up."""
    if "const" in prop:
        return prop["const"]
    if prop.get("enum"):
        return prop["enum"][0]
    if "default" in prop:
        return prop["default"]
    kind = prop.get("type")
    if kind in ("integer", "number"):
        low = prop.get("minimum", prop.get("exclusiveMinimum", 0))
        return low + (1 if "exclusiveMinimum" in prop else 0)
    if kind == "boolean":
        return False
    if kind == "string" and not prop.get("pattern") and not prop.get("format"):
        return "x" * max(1, int(prop.get("minLength", 1)))
    return None


def result_text(result: mcp_types.CallToolResult) -> str:
    """The text content of a tool result, joined."""
    return "\n".join(block.text for block in result.content if isinstance(block, mcp_types.TextContent))


def result_object(result: mcp_types.CallToolResult) -> dict[str, Any]:
    """A tool result as a JSON object; raises ``ValueError`` saying what came back instead."""
    text = result_text(result)
    if not text and isinstance(result.structured_content, dict):
        return result.structured_content  # a server that sends structured content only
    try:
        value = json.loads(text)
    except json.JSONDecodeError:
        value = None
    if not isinstance(value, dict):
        raise ValueError(
            f"expected a JSON object, got {text[:200]!r}; return a dict or a pydantic model from get_state"
        )
    return value


def control_problems(controls: Sequence[CardControl], tools: Sequence[mcp_types.Tool]) -> list[str]:
    """What is wrong with a card's controls (:mod:`rosaos.card_controls`): an unknown tool, or
    arguments the tool's input schema refuses. A control with ``shown_when`` may name a tool only
    some instances have (a ROS profile without a dock has no ``dock`` tool, and no ``docked`` key
    to show "Dock" by): when the instance under test lacks the tool, it is skipped, not failed."""
    by_name = {tool.name: tool for tool in tools}
    problems = []
    for control in controls:
        for tool_name, arguments in control.example_calls():
            tool = by_name.get(tool_name)
            if tool is None:
                if control.shown_when:
                    continue  # hidden on this instance (e.g. no dock): another profile has the tool
                problems.append(
                    f"{control.label}: no tool {tool_name!r}; tools: {', '.join(sorted(by_name))}"
                )
                continue
            try:
                jsonschema.validate(arguments, tool.input_schema)
            except jsonschema.ValidationError as error:
                problems.append(
                    f"{control.label}: {tool_name}({arguments}) is refused by its schema: {error.message}"
                )
    return problems
