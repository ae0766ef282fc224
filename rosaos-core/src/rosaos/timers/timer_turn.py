"""The offline kernel model's timer turns: set, list and cancel timers; carry out a fired one.

:class:`rosaos.models.kernel_model.LocalIntentModel` asks :func:`timer_turn` first. It answers:

- user text that is a timer request (:mod:`rosaos.timers.timer_phrases`) with a ``set_timer``,
  ``list_timers`` or ``cancel_timer`` call, once the action is a command the engine understands
  now (a timer is never set for something it could not do when it fires);
- those tools' results with one sentence ("Timer 2 set: turn off the kitchen light at 22:10
  (in 10 minutes).");
- a :class:`~rosaos.events.types.TimerFired` event with the action's ``launch_process`` calls, as if just asked, and
  their results with the acknowledgement, saying which timer it was and how late.

Anything else is left to the model (None).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from datetime import datetime
from typing import Any

from pydantic_ai.messages import ModelMessage, ModelResponsePart, TextPart, ToolCallPart

from rosaos.events.types import TimerFired
from rosaos.intents.understanding.match_result import MatchResult
from rosaos.models.conversation import (
    ToolOutcome,
    content_text,
    current_turn,
    said,
    tool_outcomes,
    turn_event,
)
from rosaos.models.turn_outcome import marked, unmatched
from rosaos.timers.timer_phrases import (
    CancelTimer,
    ListTimers,
    SetTimer,
    duration_text,
    read_timer_request,
)

Match = Callable[[str], MatchResult]
Command = Callable[[str, Sequence[str]], list[ModelResponsePart]]
Acknowledge = Callable[[list[ToolOutcome]], str]


def timer_turn(
    messages: Sequence[ModelMessage],
    tools: Sequence[str],
    match: Match,
    command: Command,
    acknowledge: Acknowledge,
    now: datetime | None = None,
) -> list[ModelResponsePart] | None:
    """The response parts when this turn is about timers, else None (see the module docstring)."""
    event = turn_event(messages)
    outcomes = tool_outcomes(current_turn(messages))
    if event is not None and isinstance(event.payload, TimerFired):
        action, head = event.payload.action, _fired_name(event.payload)
        if outcomes:
            return [TextPart(f"{head}: {acknowledge(outcomes)}")]
        parts = command(action, tools)
        if all(isinstance(part, TextPart) for part in parts):  # not understood any more: say so
            reply = " ".join(part.content for part in parts if isinstance(part, TextPart))
            return [TextPart(f"{head} fired, but I can't do it: {reply}")]
        return parts
    if outcomes:
        timer_outcomes = [outcome for outcome in outcomes if outcome.call.tool_name.endswith("_timer")
                          or outcome.call.tool_name.endswith("list_timers")]  # fmt: skip
        return [TextPart(_reply(timer_outcomes))] if timer_outcomes else None
    text = said(event)
    if text is None:
        return None
    request = read_timer_request(text, (now or datetime.now()).astimezone())
    if request is None:
        return None
    if isinstance(request, ListTimers):
        return _call(tools, "list_timers", {})
    if isinstance(request, CancelTimer):
        args = {"timer_id": request.timer_id, "matching": request.matching, "cancel_all": request.cancel_all}
        return _call(tools, "cancel_timer", {key: value for key, value in args.items() if value})
    return _set(request, text, tools, match)


def is_timer_sentence(text: str, match: Match) -> bool:
    """Whether ``text`` is a timer request the engine answers completely (for prefer_local routing)."""
    request = read_timer_request(text, datetime.now().astimezone())
    if isinstance(request, SetTimer):
        return (
            bool(request.action)
            and match(request.action).is_exact
            and not (request.weak and match(text).is_exact)
        )
    return request is not None


def _set(request: SetTimer, said: str, tools: Sequence[str], match: Match) -> list[ModelResponsePart] | None:
    if request.weak and match(said).is_exact:  # "set the volume at 20" is a setting, not a timer
        return None
    if not request.action:
        return [
            marked(
                "What should the timer do? Say, for example, 'turn off the kitchen light in ten minutes'.",
                "needs_answer",
            )
        ]
    understood = match(request.action)
    if understood.kind == "clarify":  # a bare answer would not carry the timer: ask for all of it
        return [marked(f"{understood.reply} Please say the timer again with the name.", "needs_answer")]
    if not understood.is_exact:
        return [marked(f"I can't set a timer for that: {understood.reply}", unmatched(understood))]
    timing: dict[str, Any] = {"in_seconds": request.in_seconds} if request.in_seconds else {"at": request.at}
    return _call(tools, "set_timer", {"action": request.action, **timing})


def _call(tools: Sequence[str], name: str, args: dict[str, Any]) -> list[ModelResponsePart]:
    tool = next((tool for tool in tools if tool == name or tool.endswith(name)), None)
    if tool is None:  # an agent built without the timer tools (a test, an old config): say so
        return [TextPart(f"Timers are not available here (no {name} tool).")]
    return [ToolCallPart(tool, args)]


def _fired_name(fired: TimerFired) -> str:
    """How to name a fired timer to the user: "Timer 3", or "Timer 3 (2 h late: …)"."""
    name = f"Timer {fired.timer_id}"
    if fired.late:
        name += f" ({duration_text(fired.late_seconds)} late: the kernel was not running when it was due)"
    return name


def _reply(outcomes: list[ToolOutcome]) -> str:
    replies = []
    for outcome in outcomes:
        tool = outcome.call.tool_name
        if not outcome.ok:
            what = "set that timer" if tool.endswith("set_timer") else "do that"
            replies.append(f"I couldn't {what}: {content_text(outcome.content)}")
            continue
        result = _result(outcome.content)
        if tool.endswith("set_timer") and isinstance(result, dict):
            replies.append(
                f"Timer {result['id']} set: {result['action']} {result.get('when', '')}".strip() + "."
            )
        elif tool.endswith("list_timers") and isinstance(result, list):
            replies.append(_listing(result))
        elif isinstance(result, list):
            replies.append(_cancelled(result))
        else:
            replies.append(content_text(outcome.content))
    return " ".join(replies)


def _result(content: Any) -> Any:
    """A tool's structured result: FastMCP wraps a list in ``{"result": [...]}``."""
    if isinstance(content, dict) and set(content) == {"result"}:
        return content["result"]
    return content


def _listing(timers: list[Any]) -> str:
    if not timers:
        return "No timers are set."
    items = "; ".join(f"{timer['id']}: {timer['action']} {timer.get('when', '')}".strip() for timer in timers)
    return f"{len(timers)} timer{'s' if len(timers) != 1 else ''}: {items}."


def _cancelled(timers: list[Any]) -> str:
    items = "; ".join(f"{timer['id']} ({timer['action']})" for timer in timers)
    if len(timers) == 1:
        return f"Cancelled timer {items}: it will not run."
    return f"Cancelled timers {items}: they will not run."
