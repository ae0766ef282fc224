"""How a kernel turn ended, read from its messages: the engine's mark, or every tool call refused.

The reply's words are never read: an LLM that says "sorry, I can't" without calling a tool is
``done`` (it answered); one whose every call was refused is ``refused``, whatever it says after.
"""

from __future__ import annotations

from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    TextPart,
    ToolCallPart,
    ToolReturnPart,
    UserPromptPart,
)

from rosaos.models.turn_outcome import marked, turn_outcome


def turn(*steps: ModelMessage) -> list[ModelMessage]:
    return [ModelRequest(parts=[UserPromptPart("[User typed] turn on the fan")]), *steps]


def launch(call_id: str, device: str) -> ModelResponse:
    return ModelResponse(parts=[ToolCallPart("launch_process", {"devices": [device]}, tool_call_id=call_id)])


def refused(call_id: str) -> ModelRequest:
    return ModelRequest(
        parts=[
            ToolReturnPart("launch_process", "unknown device 'fan'", tool_call_id=call_id, outcome="failed")
        ]
    )


def retried(call_id: str) -> ModelRequest:
    """A call to be made again (a ``ModelRetry``), as pydantic-ai records it now."""
    content = "unknown device 'fan'"
    return ModelRequest(
        parts=[ToolReturnPart("launch_process", content, tool_call_id=call_id, outcome="retried")]
    )


def launched(call_id: str) -> ModelRequest:
    return ModelRequest(parts=[ToolReturnPart("launch_process", {"process_id": 1}, tool_call_id=call_id)])


def said(text: str) -> ModelResponse:
    return ModelResponse(parts=[TextPart(text)])


def test_the_engines_mark_on_its_final_text_is_the_outcome() -> None:
    reply = ModelResponse(parts=[marked("Which one do you mean: kitchen light or lamp?", "needs_answer")])
    assert turn_outcome(turn(reply)) == "needs_answer"


def test_a_turn_whose_every_tool_call_was_refused_is_refused() -> None:
    assert turn_outcome(turn(launch("a", "fan"), refused("a"), said("I could not."))) == "refused"
    assert turn_outcome(turn(launch("a", "fan"), retried("a"), said("There is no fan."))) == "refused"


def test_one_accepted_call_makes_it_done() -> None:
    steps = [launch("a", "fan"), retried("a"), launch("b", "kitchen_light"), launched("b"), said("On it.")]
    assert turn_outcome(turn(*steps)) == "done"


def test_words_alone_are_an_answer_whatever_they_say() -> None:
    assert turn_outcome(turn(said("Sorry, I can't do that: there is no fan."))) == "done"
