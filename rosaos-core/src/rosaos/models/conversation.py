"""Reading a pydantic-ai conversation the way the offline models need: events, tool calls, results.

The local models are stateless: every request carries the whole conversation, so what to do next
is read off the last messages (the kernel event being handled, the tool calls already made and
what they returned). This module holds that reading, shared by the kernel and process models.
"""

from __future__ import annotations

import ast
import json
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    RetryPromptPart,
    SystemPromptPart,
    ToolCallPart,
    ToolReturnPart,
    UserPromptPart,
)

from rosaos.receipts import RECEIPTS_HEADING

EVENT_TAG = re.compile(r"^\[(?P<tag>[A-Za-z ]+)\]\s?(?P<body>.*)$", re.DOTALL)
_TASK = re.compile(r"\stask=(?P<task>(?:'.*'|\".*\"))$")
_STATUS = re.compile(r"\bstatus=(?P<status>\w+)")
_WORKER = re.compile(r"\bworker=(?P<worker>\d+)")


@dataclass(frozen=True)
class KernelEvent:
    """A rendered kernel event: ``[User said] hello`` → tag ``User said``, body ``hello``."""

    tag: str | None
    body: str


@dataclass(frozen=True)
class WorkerCallbackEvent:
    """The fields of a ``[Worker callback]`` event body."""

    worker: int | None
    status: str
    task: str | None
    output: str | None
    error: str | None


@dataclass(frozen=True)
class ToolOutcome:
    """A tool call and how it ended."""

    call: ToolCallPart
    ok: bool
    content: Any


def parse_event(text: str) -> KernelEvent:
    """Split a rendered event into its tag and body; untagged text has tag None."""
    match = EVENT_TAG.match(text.strip())
    if match is None:
        return KernelEvent(None, text.strip())
    return KernelEvent(match.group("tag"), match.group("body").strip())


def parse_callback(body: str) -> WorkerCallbackEvent:
    """Read a ``[Worker callback]`` body as :func:`rosaos.kernel.loop.render_event` writes it."""
    head, _, rest = body.partition("\n")
    status = _STATUS.search(head)
    worker = _WORKER.search(head)
    task: str | None = None
    if (found := _TASK.search(head)) is not None:
        try:
            task = str(ast.literal_eval(found.group("task")))
        except (ValueError, SyntaxError):
            task = None
    output = error = None
    rest = rest.split(f"\n{RECEIPTS_HEADING}", 1)[0]  # the receipts follow the output or error
    rest, _, report = rest.partition("\nreport: ")  # a failure's report follows its error
    if rest.startswith("error:"):
        error = _unquoted(rest[len("error:") :])
        output = _unquoted(report) if report else None
    elif rest.startswith("output:"):
        output = _unquoted(rest[len("output:") :])
    return WorkerCallbackEvent(
        worker=int(worker.group("worker")) if worker else None,
        status=status.group("status") if status else "unknown",
        task=task,
        output=output,
        error=error,
    )


def _unquoted(text: str) -> str:
    """A rendered value: JSON strings (how event_text quotes data) decoded, other text as it is."""
    text = text.strip()
    if text.startswith('"'):
        try:
            value = json.loads(text)
        except ValueError:
            return text
        if isinstance(value, str):
            return value.strip()
    return text


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


def prompt_texts(messages: Sequence[ModelMessage], instructions: str | None) -> list[str]:
    """Every text the run was given: user prompts, system prompts and instructions."""
    texts = [instructions] if instructions else []
    for message in messages:
        if not isinstance(message, ModelRequest):
            continue
        if message.instructions:
            texts.append(message.instructions)
        for part in message.parts:
            if isinstance(part, SystemPromptPart):
                texts.append(part.content)
            elif isinstance(part, UserPromptPart):
                texts.append(user_text(ModelRequest(parts=[part])) or "")
    return texts


def content_text(content: Any) -> str:
    """A tool result or error as one readable string."""
    if isinstance(content, str):
        return content.strip()
    if isinstance(content, list) and content and isinstance(content[0], dict) and "msg" in content[0]:
        return "; ".join(str(item.get("msg")) for item in content)  # pydantic validation errors
    return str(content)
