"""The offline turn records a call to be made again as pydantic-ai 2.68 wants it.

``RetryPromptPart`` is deprecated (a ``PydanticAIDeprecationWarning`` on every construction): a
retry that answers a tool call is that call's own ``ToolReturnPart`` with ``outcome="retried"``.
The kernel loop reads a launch or stop that was not a success from ``outcome`` (a refusal notice),
so the retried part must carry the same words the model and the user are shown.
"""

from __future__ import annotations

import warnings
from datetime import UTC, datetime

from pydantic_ai import ModelRetry
from pydantic_ai.messages import ModelMessage, ModelResponse, TextPart, ToolCallPart, ToolReturnPart
from pydantic_ai.models.function import AgentInfo, FunctionModel
from pydantic_ai.toolsets import FunctionToolset

from rosaos.events.types import Event, UserText
from rosaos.kernel.loop import tool_activity
from rosaos.kernel.offline_turn import offline_turn


def _toolset() -> FunctionToolset[None]:
    toolset: FunctionToolset[None] = FunctionToolset()

    @toolset.tool_plain
    def launch_process(task: str) -> str:
        """Refuses every task, as a launch the kernel may not make is refused."""
        raise ModelRetry(f"no device can do {task!r}; name one of the listed devices")

    return toolset


def _model() -> FunctionModel:
    """Calls a tool that does not exist and a launch that is refused, then answers in text."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        if len(messages) == 1:
            return ModelResponse(
                parts=[
                    ToolCallPart("open_garage", {}, tool_call_id="a"),
                    ToolCallPart("launch_process", {"task": "fly"}, tool_call_id="b"),
                ]
            )
        return ModelResponse(parts=[TextPart("I cannot do that.")])

    return FunctionModel(respond)


async def test_an_unknown_tool_and_a_model_retry_come_back_as_retried_returns_without_a_warning() -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a PydanticAIDeprecationWarning would fail the turn
        turn = await offline_turn(
            _model(),
            _toolset(),
            Event(
                id=1, time=datetime.now(UTC), kind="user_typed", source="test", payload=UserText(text="fly")
            ),
            "[User typed] fly",
            history=[],
            instructions="You are the kernel.",
            request_limit=3,
        )
    assert turn.output == "I cannot do that."
    returns = {
        part.tool_call_id: part
        for message in turn.new_messages
        for part in message.parts
        if isinstance(part, ToolReturnPart)
    }
    unknown, refused = returns["a"], returns["b"]
    assert (unknown.outcome, unknown.retry and unknown.retry.cause) == ("retried", "unknown_tool")
    assert "Unknown tool name: 'open_garage'" in str(unknown.content)
    assert (refused.outcome, refused.retry and refused.retry.cause) == ("retried", "model_retry")
    # The loop turns the refused launch into a notice with the tool's own words.
    notices = [text for kind, text, _ in tool_activity(turn.new_messages) if kind == "notice"]
    assert len(notices) == 1
    assert notices[0].startswith("launch refused:") and "no device can do 'fly'" in notices[0]
