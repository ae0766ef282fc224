"""A process model for the receipt tests: calls each scripted tool once, then reports."""

from __future__ import annotations

from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    TextPart,
    ToolCallPart,
    ToolReturnPart,
)
from pydantic_ai.models.function import AgentInfo, FunctionModel

SCRIPT = [("set_pin", {"pin": "1234", "label": "front door"}), ("move", {"speed": 2.0}), ("nudge", {})]


def calls_each_scripted_tool() -> FunctionModel:
    """One tool per request, in :data:`SCRIPT` order (a failed call does not stop it), then "done"."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        done = sum(
            1
            for message in messages
            if isinstance(message, ModelRequest)
            for part in message.parts
            if isinstance(part, ToolReturnPart) or type(part).__name__ == "RetryPromptPart"
        )
        if done < len(SCRIPT):
            name, args = SCRIPT[done]
            return ModelResponse(parts=[ToolCallPart(name, args)])
        return ModelResponse(parts=[TextPart("done")])

    return FunctionModel(respond, model_name="calls-each-scripted-tool")
