"""How the offline engine answers a :class:`~rosaos.events.types.DeviceNotice`: tell the user when it matters, else nothing.

A ``notify`` notice becomes one process on the user-interface device (the Reachy Mini) that says
the driver's sentence with its ``speak`` tool. An ``info`` notice gets no reply at all: the web
page and an open ``rosaos chat`` show it, and nobody is interrupted. Rate limits and deduplication happen
before the event is queued (:mod:`rosaos.notices.notice_watcher`), so every notice that reaches here is
worth its one sentence.
"""

from __future__ import annotations

from pydantic_ai.messages import ModelResponsePart, TextPart, ToolCallPart

from rosaos.events.plan import Plan, PlanStep, launch_args
from rosaos.events.types import DeviceNotice

SPEAK_TOOL = "speak"
SILENCE = " "
"""The reply that says nothing: the kernel loop publishes no blank reply, and pydantic-ai would
ask an empty response again."""


def notice_response(notice: DeviceNotice, speaker: str | None, launch: str | None) -> list[ModelResponsePart]:
    """The kernel's response to ``notice``; ``speaker`` is the always-attached device."""
    if notice.importance != "notify":
        return [TextPart(SILENCE)]
    if speaker is None or launch is None:  # nothing to speak with: the updates stream still shows it
        return [TextPart(notice.message)]
    plan = Plan(
        steps=[PlanStep(device=speaker, tool=SPEAK_TOOL, args={"text": notice.message})],
        reply=notice.message,
        ack=notice.message,
        quiet=True,
    )
    summary = f"Tell the user: {notice.message}"
    return [ToolCallPart(launch, launch_args(summary, [speaker], plan))]
