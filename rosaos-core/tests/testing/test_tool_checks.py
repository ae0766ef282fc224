"""The pure checks behind the conformance kit (rosaos.testing.tool_checks)."""

from __future__ import annotations

from typing import Any

import mcp_types
import pytest

from rosaos.testing.tool_checks import (
    OutOfRangeCall,
    missing_annotations,
    out_of_range_candidates,
    result_object,
    untyped_arguments,
)


def tool(
    name: str, properties: dict[str, Any], required: list[str] | None = None, **hints: bool
) -> mcp_types.Tool:
    schema = {"type": "object", "properties": properties, "required": required or list(properties)}
    annotations = mcp_types.ToolAnnotations(**hints) if hints else None
    return mcp_types.Tool(name=name, description="A tool.", input_schema=schema, annotations=annotations)


def text_result(text: str, structured: dict[str, Any] | None = None) -> mcp_types.CallToolResult:
    content = [mcp_types.TextContent(type="text", text=text)] if text else []
    return mcp_types.CallToolResult(content=content, structured_content=structured)


def test_the_out_of_range_call_prefers_the_tool_with_fewest_required_arguments() -> None:
    hue = {"type": "integer", "minimum": 0, "maximum": 360}
    saturation = {"type": "integer", "minimum": 0, "maximum": 100}
    tools = [tool("set_color", {"hue": hue, "saturation": saturation}), tool("set_hue", {"hue": hue})]
    assert out_of_range_candidates(tools)[0] == OutOfRangeCall("set_hue", {"hue": 361}, ("hue",))


def test_other_required_arguments_get_valid_values() -> None:
    properties = {
        "level": {"type": "number", "maximum": 1.0},
        "mode": {"type": "string", "enum": ["eco", "boost"]},
        "ramp": {"type": "integer", "exclusiveMinimum": 0},
    }
    [call] = out_of_range_candidates([tool("set", properties)])
    assert call.args == {"level": 1.5, "mode": "eco", "ramp": 1}


def test_an_exclusive_maximum_is_itself_out_of_range() -> None:
    [call] = out_of_range_candidates([tool("set", {"speed": {"type": "integer", "exclusiveMaximum": 10}})])
    assert call.args == {"speed": 10}


def test_no_candidate_when_another_required_argument_cannot_be_made_up() -> None:
    properties = {"level": {"type": "integer", "maximum": 100}, "pose": {"$ref": "#/$defs/Pose"}}
    assert out_of_range_candidates([tool("go", properties)]) == []


def test_typed_arguments_include_unions_enums_and_references() -> None:
    properties = {
        "a": {"anyOf": [{"type": "integer"}, {"type": "null"}]},
        "b": {"enum": ["x"]},
        "c": {"$ref": "#/$defs/C"},
        "d": {"description": "anything goes"},
    }
    assert untyped_arguments([tool("t", properties)]) == [
        "t(d): untyped argument; annotate it (e.g. int, Literal[...])"
    ]


def test_both_hints_must_be_explicit() -> None:
    tools = [
        tool("read", {}, read_only_hint=True),
        tool("write", {}, read_only_hint=False, destructive_hint=True),
    ]
    assert missing_annotations(tools) == [
        "read: destructiveHint not set; pass annotations={'destructiveHint': ...} to @tool"
    ]


def test_a_state_result_is_read_from_its_json_text() -> None:
    assert result_object(text_result('{"on": true}')) == {"on": True}


def test_a_structured_only_result_is_accepted() -> None:
    assert result_object(text_result("", {"on": True})) == {"on": True}


@pytest.mark.parametrize("text", ["fine", "[1, 2]"])
def test_anything_but_a_json_object_is_refused(text: str) -> None:
    with pytest.raises(ValueError, match="expected a JSON object"):
        result_object(text_result(text, {"result": text}))
