"""The offline engine plans "stop" and state questions as lease-free kernel tool calls."""

from __future__ import annotations

from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    TextPart,
    ToolCallPart,
    ToolReturnPart,
)

from rosaos.events.types import Event
from rosaos.kernel.event_text import render_event
from rosaos.models.conversation import event_request
from rosaos.models.kernel_actions import help_text
from rosaos.models.kernel_model import LocalIntentModel
from rosaos.notices.notice_plan import SILENCE

from ..intents import engine_turns
from ..intents.intents_support import home_world

TOOLS = ["launch_process", "terminate_process", "stop", "device_state"]
MODEL = LocalIntentModel(home_world())


def request(event: Event) -> ModelRequest:
    """The kernel's request for ``event``: the typed event for the engine, the text for an LLM."""
    return event_request(event, render_event(event))


def said(text: str) -> list[ModelMessage]:
    return [request(engine_turns.said(text))]


def test_a_stop_is_a_stop_call_and_its_summary_is_the_reply() -> None:
    messages = said("okay, enough, halt the turtlebot")
    [call] = MODEL.respond(messages, TOOLS)
    assert isinstance(call, ToolCallPart) and call.tool_name == "stop"
    assert call.args_as_dict() == {"devices": ["turtlebot"]}
    summary = "Stopped the turtlebot: it was doing 'Search for a person' (process 4), now terminated."
    result = {"devices": [], "terminated": [{"id": 4, "task": "Search for a person"}], "summary": summary}
    messages += [
        ModelResponse(parts=[call]),
        ModelRequest(parts=[ToolReturnPart("stop", result, tool_call_id=call.tool_call_id)]),
    ]
    [reply] = MODEL.respond(messages, TOOLS)
    assert isinstance(reply, TextPart) and reply.content == summary

    # The callback of the process the stop ended gets no second reply.
    messages += [ModelResponse(parts=[reply], model_name=MODEL.model_name)]
    callback = engine_turns.callback(4, status="terminated", task="Search for a person", error="terminated")
    [quiet] = MODEL.respond([*messages, request(callback)], TOOLS)
    assert isinstance(quiet, TextPart) and quiet.content == SILENCE


def test_a_question_reads_device_state_and_answers_yes_or_no_first() -> None:
    messages = said("is the kitchen light on?")
    [call] = MODEL.respond(messages, TOOLS)
    assert isinstance(call, ToolCallPart) and call.tool_name == "device_state"
    assert call.args_as_dict() == {"device": "kitchen_light"}
    state = {"device": "kitchen_light", "state": {"on": True, "brightness": 40}, "held_by": [], "said": []}
    messages += [
        ModelResponse(parts=[call]),
        ModelRequest(parts=[ToolReturnPart("device_state", state, tool_call_id=call.tool_call_id)]),
    ]
    [reply] = MODEL.respond(messages, TOOLS)
    assert isinstance(reply, TextPart) and reply.content == "Yes, the kitchen light is on, at 40% brightness."


def test_without_the_lease_free_tools_the_engine_plans_as_before() -> None:
    parts = MODEL.respond(said("is the kitchen light on?"), ["launch_process"])
    assert [part.tool_name for part in parts if isinstance(part, ToolCallPart)] == ["launch_process"]


def test_what_can_you_do_names_this_worlds_devices() -> None:
    text = help_text(home_world())
    assert "kitchen light" in text and "stop" in text
