"""Action goals: send them, follow their feedback, wait, cancel, and remember the recent ones.

A goal outlives the tool call that sent it when asked to (``wait=False``), so ``goal_status``
and ``cancel_goal`` work on it later; ``safe_stop`` cancels every goal still running.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections import OrderedDict
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

from rosaos.drivers import DeviceError
from rosaos_ros.bridge import GoalHandle, RosbridgeClient
from rosaos_ros.messages import summarize

STATUS_NAMES = {
    0: "unknown",
    1: "accepted",
    2: "executing",
    3: "canceling",
    4: "succeeded",
    5: "canceled",
    6: "aborted",
}
KEEP = 20
"""Finished goals remembered for goal_status."""
CANCEL_WAIT = 3.0
"""Seconds to wait for an action server to confirm a cancel."""

FeedbackCallback = Callable[[int, dict[str, Any]], Awaitable[None]]


@dataclass
class GoalRecord:
    """One goal, as ``goal_status`` reports it."""

    goal_id: str
    action: str
    action_type: str
    handle: GoalHandle
    status: str = "running"
    started: float = field(default_factory=time.monotonic)
    seconds: float | None = None
    feedback_count: int = 0
    last_feedback: dict[str, Any] | None = None
    result: Any = None
    error: str | None = None
    done: asyncio.Event = field(default_factory=asyncio.Event)
    listeners: list[asyncio.Queue[tuple[int, dict[str, Any]]]] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        """The record for the model (feedback and result summarised)."""
        report: dict[str, Any] = {
            "goal_id": self.goal_id,
            "action": self.action,
            "status": self.status,
            "seconds": round(
                self.seconds if self.seconds is not None else time.monotonic() - self.started, 2
            ),
            "feedback_count": self.feedback_count,
            "last_feedback": summarize(self.last_feedback),
        }
        if self.done.is_set():
            report["result"] = summarize(self.result)
        if self.error:
            report["error"] = self.error
        return report


class GoalTracker:
    """The goals of one robot instance."""

    def __init__(self, bridge: RosbridgeClient) -> None:
        self.bridge = bridge
        self.goals: OrderedDict[str, GoalRecord] = OrderedDict()
        self._watchers: set[asyncio.Task[None]] = set()

    async def send(
        self,
        action: str,
        action_type: str,
        goal: dict[str, Any],
        *,
        timeout: float,
        wait: bool = True,
        on_feedback: FeedbackCallback | None = None,
    ) -> GoalRecord:
        """Send a goal; with ``wait``, return when it ends or ``timeout`` passes (then it is cancelled)."""
        handle = self.bridge.send_goal(action, action_type, goal)
        record = GoalRecord(handle.goal_id, action, action_type, handle)
        self._remember(record)
        watcher = asyncio.get_running_loop().create_task(self._watch(record))
        self._watchers.add(watcher)
        watcher.add_done_callback(self._watchers.discard)
        if not wait:
            return record
        progress: asyncio.Queue[tuple[int, dict[str, Any]]] = asyncio.Queue()
        record.listeners.append(progress)
        deadline = time.monotonic() + timeout
        try:
            while not record.done.is_set():
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    await self._cancel(record, f"no result within {timeout:g} s, so the goal was cancelled")
                    break
                next_feedback = asyncio.ensure_future(progress.get())
                finished = asyncio.ensure_future(record.done.wait())
                done, pending = await asyncio.wait(
                    {next_feedback, finished}, timeout=remaining, return_when=asyncio.FIRST_COMPLETED
                )
                for task in pending:
                    task.cancel()
                if next_feedback in done and on_feedback is not None:
                    count, values = next_feedback.result()
                    await on_feedback(count, values)
        except asyncio.CancelledError:
            handle.cancel()  # the caller went away: a goal nobody waits for is not left running
            raise
        finally:
            record.listeners.remove(progress)
        return record

    def get(self, goal_id: str) -> GoalRecord:
        """The goal ``goal_id``; :class:`DeviceError` listing the known ones otherwise."""
        record = self.goals.get(goal_id)
        if record is None:
            known = ", ".join(self.goals) or "none yet"
            raise DeviceError(f"{self.bridge.instance}: no goal {goal_id!r}; known goals: {known}")
        return record

    async def cancel(self, goal_id: str) -> GoalRecord:
        """Cancel a running goal and wait (briefly) for the action server to confirm."""
        record = self.get(goal_id)
        if not record.done.is_set():
            await self._cancel(record, None)
        return record

    def cancel_all(self) -> list[str]:
        """Ask every running goal's server to cancel (no waiting); returns their ids."""
        running = [record for record in self.goals.values() if not record.done.is_set()]
        for record in running:
            with contextlib.suppress(DeviceError):
                record.handle.cancel()
        return [record.goal_id for record in running]

    async def close(self) -> None:
        """Cancel what runs and stop watching."""
        self.cancel_all()
        for watcher in list(self._watchers):
            watcher.cancel()

    async def _cancel(self, record: GoalRecord, reason: str | None) -> None:
        if self.bridge.connected:
            record.handle.cancel()
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(record.done.wait(), CANCEL_WAIT)
        if not record.done.is_set():
            record.status = "cancel requested"
        if reason:
            record.error = reason

    async def _watch(self, record: GoalRecord) -> None:
        pump = asyncio.ensure_future(self._pump_feedback(record))
        try:
            status, values = await record.handle.result
            record.status = STATUS_NAMES.get(status, "unknown")
            record.result = values
        except DeviceError as error:
            record.status = "failed"
            record.error = str(error)
        finally:
            while not record.handle.feedback.empty():  # feedback that arrived with the result
                self._feedback(record, record.handle.feedback.get_nowait())
            pump.cancel()
            record.seconds = time.monotonic() - record.started
            record.done.set()

    async def _pump_feedback(self, record: GoalRecord) -> None:
        while True:
            self._feedback(record, await record.handle.feedback.get())

    def _feedback(self, record: GoalRecord, values: dict[str, Any]) -> None:
        record.feedback_count += 1
        record.last_feedback = values
        for listener in record.listeners:
            listener.put_nowait((record.feedback_count, values))

    def _remember(self, record: GoalRecord) -> None:
        self.goals[record.goal_id] = record
        finished = [goal_id for goal_id, r in self.goals.items() if r.done.is_set()]
        for goal_id in finished[: max(0, len(finished) - KEEP)]:
            del self.goals[goal_id]
