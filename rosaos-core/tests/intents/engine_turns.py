"""Turns of the offline engine as the kernel loop runs them: a typed event in, the reply out.

The kernel hands the local-intent engine the :class:`~rosaos.events.types.Event` itself
(:func:`rosaos.kernel.offline_turn.offline_turn`); the rendered text rides along only for an LLM
that reads the history later. These helpers build such events and run such turns against a
real in-process FastMCP ``launch_process`` (and whatever else a test adds to it).
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

from fastmcp import FastMCP
from pydantic_ai.mcp import MCPToolset
from pydantic_ai.messages import ModelMessage, ModelResponse

from rosaos.events.callback import ProcessStatus, WorkerCallback
from rosaos.events.plan import Plan
from rosaos.events.types import DeviceNotice, ErrorReport, Event, TimerFired, UserText
from rosaos.kernel.event_text import render_event
from rosaos.kernel.offline_turn import offline_turn
from rosaos.models.kernel_model import LocalIntentModel


def event(kind: str, payload: Any, event_id: int = 1) -> Event:
    """A stored event of ``kind`` (as the kernel loop reads it from the queue)."""
    return Event(id=event_id, time=datetime.now(UTC), kind=kind, source="test", payload=payload)


def said(text: str) -> Event:
    """The user said ``text`` (voice)."""
    return event("user_said", UserText(text=text))


def callback(
    process: int,
    *,
    status: ProcessStatus = "ok",
    task: str = "a task",
    plan: Plan | None = None,
    output: str | None = None,
    error: str | None = None,
) -> Event:
    """A process's callback: how it ended, its task and plan."""
    payload = WorkerCallback(
        process_id=process, status=status, task=task, plan=plan, output=output, error=error
    )
    return event("worker_callback", payload)


def notice(device: str, message: str, **fields: Any) -> Event:
    """A device notice."""
    return event("device_notice", DeviceNotice(device=device, message=message, **fields))


def error(message: str) -> Event:
    """An error report."""
    return event("error", ErrorReport(message=message))


def timer_fired(timer_id: int, action: str, late_seconds: float = 0.0) -> Event:
    """A timer fell due."""
    fired = TimerFired(timer_id=timer_id, action=action, due=datetime.now(UTC), late_seconds=late_seconds)
    return event("timer_fired", fired)


class EngineKernel:
    """The offline engine with a kernel's tools (``tools``), keeping the kernel's history."""

    def __init__(
        self, model: LocalIntentModel, tools: FastMCP, instructions: str = "You are the kernel."
    ) -> None:
        self.model = model
        self.toolset = MCPToolset(tools)
        self.instructions = instructions
        self.history: list[ModelMessage] = []

    async def say(self, said_or_event: str | Event) -> str:
        """One kernel turn: a string is the user's words (``user_said``), an event is itself."""
        handled = said(said_or_event) if isinstance(said_or_event, str) else said_or_event
        async with self.toolset:
            turn = await offline_turn(
                self.model,
                self.toolset,
                handled,
                render_event(handled),
                history=self.history,
                instructions=self.instructions,
                request_limit=20,
            )
        self.history += turn.new_messages
        return turn.output

    def responses(self) -> list[ModelResponse]:
        return [message for message in self.history if isinstance(message, ModelResponse)]
