"""Card controls: what each sends, what it refuses, and the conformance kit's check of their tools."""

from __future__ import annotations

import mcp_types
import pytest
from pydantic import ValidationError

from rosaos.card_controls import ControlValueError, button, choice, prompt, slider, toggle
from rosaos.testing.tool_checks import control_problems

LEVEL = mcp_types.Tool(
    name="set_level",
    input_schema={
        "type": "object",
        "properties": {"level": {"type": "integer", "minimum": 0, "maximum": 100}},
        "required": ["level"],
    },
)
ON = mcp_types.Tool(name="turn_on", input_schema={"type": "object", "properties": {}})
OFF = mcp_types.Tool(name="turn_off", input_schema={"type": "object", "properties": {}})


def test_each_kind_of_control_makes_its_call() -> None:
    assert toggle("Power", on_tool="turn_on", off_tool="turn_off", key="on").call(False) == ("turn_off", {})
    assert slider("Level", tool="set_level", argument="level").call(40.0) == ("set_level", {"level": 40})
    assert choice("Colour", tool="set_color_name", argument="name", options=["red"]).call("red") == (
        "set_color_name",
        {"name": "red"},
    )
    assert prompt("Say", tool="speak", argument="text").call("  hello ") == ("speak", {"text": "hello"})
    assert button("Next", "next_track").call() == ("next_track", {})


def test_a_value_that_does_not_fit_is_refused_with_what_fits() -> None:
    with pytest.raises(ControlValueError, match="outside 0-100"):
        slider("Level", tool="set_level", argument="level").call(101)
    with pytest.raises(ControlValueError, match="send true"):
        toggle("Power", on_tool="turn_on", off_tool="turn_off", key="on").call("yes")
    with pytest.raises(ControlValueError, match="type some text"):
        prompt("Say", tool="speak", argument="text").call("   ")


def test_a_control_missing_what_it_needs_is_refused_when_the_driver_is_built() -> None:
    with pytest.raises(ValidationError, match="needs off_tool"):
        toggle("Power", on_tool="turn_on", off_tool="", key="on")
    with pytest.raises(ValidationError, match="needs options"):
        choice("Colour", tool="set_color_name", argument="name", options=[])


def test_the_kit_reports_an_unknown_tool_and_arguments_the_schema_refuses() -> None:
    good = [
        toggle("Power", on_tool="turn_on", off_tool="turn_off", key="on"),
        slider("Level", tool="set_level", argument="level"),
    ]
    assert control_problems(good, [LEVEL, ON, OFF]) == []
    too_far = slider("Level", tool="set_level", argument="level", max=150)
    wrong_name = slider("Dim", tool="set_level", argument="brightness")
    problems = control_problems([too_far, wrong_name, button("Next", "next_track")], [LEVEL, ON, OFF])
    assert any(p.startswith("Level: set_level({'level': 150}) is refused") for p in problems), problems
    assert any(p.startswith("Dim: set_level(") for p in problems), problems
    assert any(p.startswith("Next: no tool 'next_track'") for p in problems), problems
    # A control shown only by a state key may name a tool this instance lacks (no dock here).
    assert control_problems([button("Dock", "dock", shown_when={"docked": False})], [ON]) == []
