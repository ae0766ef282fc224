"""How kernel events read to the kernel model: one header line per event, data always quoted.

A process's report, a device's message and an error's text come from outside the kernel: a worker
model, a driver, a network. Whatever they contain, they must never read as an event of their own.
So every event starts with a header line ``[Tag] ...`` and every text that did not come from the
user is written as a JSON string (:func:`quoted`): its line breaks become ``\\n`` inside the quotes,
so no line of it can start a new ``[User typed]`` event, and a quote inside it cannot end it.
The user's own words are theirs to write, as they wrote them (a typed task may span lines): the
user is the principal these rules protect, not a source to guard against.

Several events handled in one kernel turn (:mod:`rosaos.kernel.loop` batches what arrived while the
model was thinking) are joined with a blank line; each still starts with its header.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from typing import Any

from rosaos.events.types import Event
from rosaos.notices.notice_text import render_notice
from rosaos.receipts import receipts_text
from rosaos.timers.timer_text import render_timer_fired

EVENT_SEPARATOR = "\n\n"


def quoted(text: str) -> str:
    """``text`` as one JSON string: line breaks and quotes escaped, so it stays data."""
    return json.dumps(text, ensure_ascii=False)


def render_event(event: Event) -> str:
    """The text the kernel model reads for an event, tagged by kind."""
    payload: Any = event.payload
    match event.kind:
        case "user_said":
            return f"[User said] {payload.text}"
        case "user_typed":
            return f"[User typed] {payload.text}"
        case "worker_callback":
            head = f"[Process callback] process={payload.process_id} status={payload.status}"
            if payload.task:
                head += f" task={payload.task!r}"  # repr: one line, its quotes escaped
            then = payload.then or (payload.plan.then.summary if payload.plan and payload.plan.then else None)
            if then:  # the follow-up the kernel launches only on success
                head += f" then={then!r}"
            body = (
                f"error: {quoted(payload.error)}"
                if payload.error
                else f"output: {quoted(payload.output or '(no output)')}"
            )
            if payload.error and payload.output:  # a report that came with a failure: still data
                body += f"\nreport: {quoted(payload.output)}"
            if payload.receipts:  # what was really done, whatever the output claims
                body += "\n" + receipts_text(payload.receipts)
            return f"{head}\n{body}"
        case "device_notice":
            return render_notice(payload)
        case "error":
            return f"[Error] {quoted(payload.message)}"
        case "timer_fired":
            return render_timer_fired(payload)
    return f"[{event.kind}] {quoted(str(payload))}"


def render_events(events: Sequence[Event]) -> str:
    """Several events as one prompt, oldest first, each with its own header line."""
    return EVENT_SEPARATOR.join(render_event(event) for event in events)
