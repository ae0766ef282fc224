"""Reading a pydantic-ai conversation the way the offline models need: events, tool calls, results.

The local models are stateless: every request carries the whole conversation, so what to do next
is read off the last messages (the kernel event being handled, the tool calls already made and
what they returned). This module holds that reading, shared by the kernel and process models.

The event is typed: the kernel's request carries the :class:`~rosaos.events.types.Event` in its
metadata (:func:`event_request`) beside the text an LLM reads, and the engine reads the event,
never the text. A bare string prompt (an agent run in a test, a ``python:`` model spec) is what
the user typed.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    RetryPromptPart,
    ToolCallPart,
    ToolReturnPart,
    UserPromptPart,
)

from rosaos.events.callback import WorkerCallback
from rosaos.events.types import Event, UserText

EVENT_METADATA = "rosaos_event"
"""The key under which a kernel request carries its typed event (``ModelRequest.metadata``)."""

USER_KINDS = frozenset({"user_said", "user_typed"})


@dataclass(frozen=True)
class ToolOutcome:
    """A tool call and how it ended."""

    call: ToolCallPart
    ok: bool
    content: Any


def event_request(event: Event, prompt: str, instructions: str | None = None) -> ModelRequest:
    """The kernel's request for ``event``: ``prompt`` is what an LLM reads, ``event`` what the
    offline engine reads (the typed event, so nothing rendered is ever parsed back)."""
    return ModelRequest(
        parts=[UserPromptPart(prompt)], instructions=instructions, metadata={EVENT_METADATA: event}
    )


def request_event(request: ModelRequest | None) -> Event | None:
    """The typed event a request carries; a plain prompt (an agent run on a string) is typed text.

    None when the request has neither (tool results only)."""
    if request is None:
        return None
    event = (request.metadata or {}).get(EVENT_METADATA)
    if isinstance(event, Event):
        return event
    text = user_text(request)
    if text is None:
        return None
    return typed_text(text)


def typed_text(text: str) -> Event:
    """``text`` as a ``user_typed`` event (not stored: ``id`` 0), for a prompt given as a string."""
    payload = UserText.model_construct(text=text.strip())
    return Event.model_construct(
        id=0, time=datetime.now(UTC), kind="user_typed", source="prompt", payload=payload
    )


def turn_event(messages: Sequence[ModelMessage]) -> Event | None:
    """The event the current turn answers: the one on its first request."""
    turn = current_turn(messages)
    first = next((message for message in turn if isinstance(message, ModelRequest)), last_request(messages))
    return request_event(first)


def said(event: Event | None) -> str | None:
    """What the user said or typed, when ``event`` is user text; None for any other event."""
    if event is None or event.kind not in USER_KINDS or not isinstance(event.payload, UserText):
        return None
    return event.payload.text


def callback_of(event: Event | None) -> WorkerCallback | None:
    """The process's callback, when ``event`` is one."""
    return event.payload if event is not None and isinstance(event.payload, WorkerCallback) else None


def last_request(messages: Sequence[ModelMessage]) -> ModelRequest | None:
    """The request being answered (the last message), if it is one."""
    return messages[-1] if messages and isinstance(messages[-1], ModelRequest) else None


def user_text(request: ModelRequest | None) -> str | None:
    """The text of the request's last user prompt, if it has one."""
    if request is None:
        return None
    for part in reversed(request.parts):
        if isinstance(part, UserPromptPart):
            if isinstance(part.content, str):
                return part.content
            return " ".join(item for item in part.content if isinstance(item, str))
    return None


def current_turn(messages: Sequence[ModelMessage]) -> list[ModelMessage]:
    """The messages since the last user prompt: this run's tool calls and results."""
    for index in range(len(messages) - 1, -1, -1):
        message = messages[index]
        if isinstance(message, ModelRequest) and any(isinstance(p, UserPromptPart) for p in message.parts):
            return list(messages[index:])
    return list(messages)


def tool_outcomes(messages: Sequence[ModelMessage]) -> list[ToolOutcome]:
    """Every tool call in ``messages`` that has a result, in call order."""
    calls: dict[str, ToolCallPart] = {}
    order: list[str] = []
    results: dict[str, tuple[bool, Any]] = {}
    for message in messages:
        for part in message.parts:
            if isinstance(message, ModelResponse) and isinstance(part, ToolCallPart):
                calls[part.tool_call_id] = part
                order.append(part.tool_call_id)
            elif isinstance(part, ToolReturnPart):
                results[part.tool_call_id] = (part.outcome == "success", part.content)
            elif isinstance(part, RetryPromptPart):  # older histories: a tool error asking to retry
                results[part.tool_call_id] = (False, part.content)
    return [ToolOutcome(calls[key], *results[key]) for key in order if key in results]


def report_with_accepted_calls(messages: Sequence[ModelMessage]) -> tuple[list[ToolCallPart], str] | None:
    """The tool calls of the last response and the text written beside them, when every one of
    those calls succeeded and nothing else came since; None otherwise.

    A model that writes its report (or its words for the user) in the same response as the calls
    that finish its work needs no further request once they succeed (kernel/short_turns.py,
    processes/final_call.py).
    """
    if len(messages) < 2 or not isinstance(messages[-1], ModelRequest):
        return None
    last, previous = messages[-1], messages[-2]
    if not isinstance(previous, ModelResponse) or not previous.tool_calls:
        return None
    if any(isinstance(part, UserPromptPart) for part in last.parts):
        return None
    results = [part for part in last.parts if isinstance(part, ToolReturnPart | RetryPromptPart)]
    accepted = [part for part in results if isinstance(part, ToolReturnPart) and part.outcome == "success"]
    if len(accepted) != len(previous.tool_calls) or len(results) != len(accepted):
        return None
    return list(previous.tool_calls), (previous.text or "").strip()


def responses_by(messages: Sequence[ModelMessage], model_name: str) -> bool:
    """Whether every model response in ``messages`` came from ``model_name`` (and there is one)."""
    responses = [message for message in messages if isinstance(message, ModelResponse)]
    return bool(responses) and all(response.model_name == model_name for response in responses)


def content_text(content: Any) -> str:
    """A tool result or error as one readable string."""
    if isinstance(content, str):
        return content.strip()
    if isinstance(content, list) and content and isinstance(content[0], dict) and "msg" in content[0]:
        return "; ".join(str(item.get("msg")) for item in content)  # pydantic validation errors
    return str(content)


def last_command_devices(messages: Sequence[ModelMessage], launch: str = "launch_process") -> frozenset[str]:
    """The devices the user's latest command launched processes on, before the current turn.

    "Make it green" or "a bit dimmer than that" right after "turn on the lamp" means the lamp,
    whether or not its process has ended: the launch is in the history either way. Turns started
    by other events (a callback's follow-up, a notice) are not the user's command; a command that
    launched nothing (a question) is skipped. Empty when there is none."""
    earlier = list(messages[: len(messages) - len(current_turn(messages))])
    launched: set[str] = set()
    for message in reversed(earlier):
        if isinstance(message, ModelResponse):
            for call in message.tool_calls:
                if call.tool_name.endswith(launch):
                    devices = call.args_as_dict().get("devices")
                    launched.update(d for d in devices or () if isinstance(d, str))
            continue
        event = request_event(message)
        if event is None:
            continue  # tool results inside a turn
        if said(event) is not None and launched:
            return frozenset(launched)
        launched.clear()
    return frozenset()
