"""Process models for the ROS tests that run a real worker job against the driver's MCP server.

Run in the test's process as ``python:<this module's name>:<factory>`` (the name pytest gave this
test folder's package). One knows no ROS message type (it looks the type up, then publishes); two take a
picture, one with a profile that takes images and one text-only.
"""

from __future__ import annotations

import io
import json
import re
from typing import Any

from PIL import Image
from pydantic_ai.messages import (
    BinaryContent,
    ModelMessage,
    ModelRequest,
    ModelResponse,
    TextPart,
    ToolCallPart,
    ToolReturnPart,
    UserPromptPart,
)
from pydantic_ai.models.function import AgentInfo, FunctionModel
from pydantic_ai.profiles import ModelProfile

SEEN_TOOL_CALLS: list[tuple[str, dict[str, Any]]] = []
"""Every tool call this model made, for the test to read (the worker runs in the test's process)."""


def _content(part: ToolReturnPart) -> Any:
    return json.loads(part.content) if isinstance(part.content, str) else part.content


def _task(messages: list[ModelMessage]) -> str:
    first = messages[0]
    assert isinstance(first, ModelRequest)
    return " ".join(str(part.content) for part in first.parts if isinstance(part, UserPromptPart))


def _call(name: str, args: dict[str, Any]) -> ModelResponse:
    SEEN_TOOL_CALLS.append((name, args))
    return ModelResponse(parts=[ToolCallPart(name, args)])


def looks_up_then_publishes() -> FunctionModel:
    """For a task "set <field path> to <value> on <topic>": ask for the topic's message fields, copy
    the example message, set the field the task names (checked against the schema), publish it."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        task = _task(messages)
        found = re.search(r"set ([\w.]+) to ([-\d.]+) on (/\S+)", task)
        assert found, task
        path, value, topic = found.group(1).split("."), float(found.group(2)), found.group(3)
        last = messages[-1]
        returns = (
            [p for p in last.parts if isinstance(p, ToolReturnPart)] if isinstance(last, ModelRequest) else []
        )
        if not returns:
            return _call("message_details", {"msg_type": topic})
        result = _content(returns[0])
        if returns[0].tool_name == "message_details":
            fields, msg = result["fields"], json.loads(json.dumps(result["example"]))
            target = msg
            for name in path[:-1]:
                if name not in fields or not isinstance(fields[name], dict):
                    return ModelResponse(parts=[TextPart(f"{topic} has no message field {name}")])
                fields, target = fields[name]["fields"], target[name]
            if path[-1] not in fields:
                return ModelResponse(parts=[TextPart(f"{topic} has no field {path[-1]}")])
            target[path[-1]] = value
            return _call("publish", {"topic": topic, "msg": msg})
        return ModelResponse(parts=[TextPart(f"published: {json.dumps(result)}")])

    return FunctionModel(respond, model_name="looks-up-then-publishes")


def _takes_a_picture(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
    """Call capture_image, then report what reached the model: image parts and the tool's text."""
    last = messages[-1]
    returns = (
        [p for p in last.parts if isinstance(p, ToolReturnPart)] if isinstance(last, ModelRequest) else []
    )
    if not returns:
        return ModelResponse(parts=[ToolCallPart("capture_image", {})])
    images = [
        item
        for part in last.parts
        for item in (part.content if isinstance(part.content, list) else [part.content])
        if isinstance(item, BinaryContent) and item.is_image
    ]
    sizes = [Image.open(io.BytesIO(image.data)).size for image in images]
    texts = [item for p in returns for item in (p.content if isinstance(p.content, list) else [p.content])]
    report = next(item for item in texts if isinstance(item, dict))
    return ModelResponse(parts=[TextPart(json.dumps({"images": sizes, "report": report}))])


def sees_pictures() -> FunctionModel:
    """A model whose profile takes images (pydantic-ai's default ``supports_image_input``)."""
    return FunctionModel(_takes_a_picture, model_name="sees-pictures")


def text_only() -> FunctionModel:
    """The same model, but its profile says it takes no images."""
    return FunctionModel(
        _takes_a_picture, model_name="text-only", profile=ModelProfile(supports_image_input=False)
    )
