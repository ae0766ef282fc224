"""The kernel agent's timer tools: ``set_timer``, ``list_timers``, ``cancel_timer``.

Added to the kernel's own FastMCP server (:func:`rosaos.kernel.tools.build_kernel_tools`) by
:func:`add_timer_tools`. They only touch the timer table; a fired timer comes back to the kernel
as a ``[Timer fired]`` event, and its action is then launched like any command.
"""

from __future__ import annotations

from datetime import datetime
from typing import Annotated, Any

from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from pydantic import Field

from rosaos.timers.timer_book import MAX_DELAY, Timer, TimerBook, TimerError
from rosaos.timers.timer_text import DueTimeError, due_text, resolve_due

TIMER_TOOL_NAMES = ("set_timer", "list_timers", "cancel_timer")


def timer_data(timer: Timer, now: datetime) -> dict[str, Any]:
    """A timer as the tools return it: the stored fields, plus ``when`` for people."""
    data = timer.model_dump(mode="json")
    data["due_local"] = timer.due.astimezone().isoformat(timespec="seconds")
    if timer.state == "pending":
        data["when"] = due_text(timer.due, now)
    return data


def add_timer_tools(server: FastMCP, book: TimerBook) -> None:
    """Register the three timer tools on the kernel's tool server."""

    @server.tool(annotations={"readOnlyHint": False, "destructiveHint": False, "idempotentHint": False})
    async def set_timer(
        action: Annotated[
            str,
            Field(
                min_length=1,
                max_length=4000,
                description="The command without its time ('turn off the kitchen light').",
            ),
        ],
        in_seconds: Annotated[
            float | None,
            Field(gt=0, le=MAX_DELAY.total_seconds()),
        ] = None,
        at: Annotated[
            str | None,
            Field(
                max_length=40,
                description="Or a local time: 'HH:MM' (24 h, the next one) or ISO 8601.",
            ),
        ] = None,
    ) -> dict[str, Any]:
        """Do an action later, as a [Timer fired] event (it survives restarts). Give in_seconds or at."""
        now = book.now()
        try:
            due = resolve_due(in_seconds, at, now)
            timer = await book.set(action, due)
        except (DueTimeError, TimerError) as error:
            raise ToolError(str(error)) from None
        return timer_data(timer, now)

    @server.tool(annotations={"readOnlyHint": True, "destructiveHint": False, "idempotentHint": True})
    async def list_timers() -> list[dict[str, Any]]:
        """The timers still to fire, soonest first."""
        now = book.now()
        return [timer_data(timer, now) for timer in await book.pending()]

    @server.tool(annotations={"readOnlyHint": False, "destructiveHint": True, "idempotentHint": True})
    async def cancel_timer(
        timer_id: Annotated[int | None, Field(ge=1)] = None,
        matching: Annotated[
            str | None,
            Field(
                max_length=200,
                description="Or those whose action has all these words ('light').",
            ),
        ] = None,
        cancel_all: bool = False,
    ) -> list[dict[str, Any]]:
        """Cancel timers; with no argument the newest ('that timer')."""
        now = book.now()
        targets = await _targets(book, timer_id, matching, cancel_all)
        cancelled = []
        for target in targets:
            try:
                cancelled.append(await book.cancel(target))
            except KeyError:
                raise ToolError(f"no timer {target}; list_timers shows the pending ones") from None
            except TimerError as error:
                raise ToolError(str(error)) from None
        return [timer_data(timer, now) for timer in cancelled]


async def _targets(
    book: TimerBook, timer_id: int | None, matching: str | None, cancel_all: bool
) -> list[int]:
    """The ids a cancel_timer call means; raises ToolError when it means none."""
    if timer_id is not None:
        return [timer_id]
    pending = await book.pending()
    if not pending:
        raise ToolError("no timer is set, so there is nothing to cancel")
    if cancel_all:
        return [timer.id for timer in pending]
    if matching:
        words = matching.lower().split()
        found = [timer.id for timer in pending if all(word in timer.action.lower() for word in words)]
        if not found:
            actions = "; ".join(f"{timer.id}: {timer.action}" for timer in pending)
            raise ToolError(f"no pending timer's action mentions {matching!r}; the timers are {actions}")
        return found
    return [max(pending, key=lambda timer: timer.id).id]  # ids only grow: the newest
