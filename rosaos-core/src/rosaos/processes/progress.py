"""Progress of a long tool call (a search), from the device to ``rosaos ps`` and ``GET /processes``.

A device tool reports progress the MCP way (``await ctx.report_progress(done, total, message)``).
In the worker, every device session's client has a progress handler (:meth:`ProgressRelay.handler`)
that writes a ``progress`` protocol line for the job running now; the pool's watcher passes it to
the process manager, which keeps the latest on the process's :class:`ProcessProgress`. Nothing
is stored: progress is for people watching, and a finished process's result says the rest.
"""

from __future__ import annotations

import math
from collections.abc import Awaitable, Callable
from datetime import UTC, datetime
from typing import Any, Protocol

from pydantic import BaseModel, Field, computed_field


class ProcessProgress(BaseModel):
    """How far a process's current tool call is, as the device last reported it."""

    device: str
    progress: float
    total: float | None = None
    message: str | None = Field(default=None, max_length=500)
    time: datetime

    @computed_field  # type: ignore[prop-decorator]
    @property
    def percent(self) -> int | None:
        """Whole percent done, when the device gave a total."""
        if not self.total or self.total <= 0:
            return None
        return max(0, min(100, int(100 * self.progress / self.total)))

    def line(self) -> str:
        """One short line for ``rosaos ps``: ``42% searching: 3 of 8 views``."""
        head = f"{self.percent}%" if self.percent is not None else f"{self.progress:g}"
        return f"{head} {self.message}" if self.message else head


class _Sink(Protocol):
    def send(self, event: dict[str, Any]) -> None: ...


class ProgressRelay:
    """In a worker: turns MCP progress notifications into protocol lines for the current job."""

    def __init__(self) -> None:
        self.sink: _Sink | None = None
        self.process_id: int | None = None
        """The job running now (a worker runs one at a time); None between jobs."""

    def handler(self, device: str) -> Callable[[float, float | None, str | None], Awaitable[None]]:
        """The progress handler for ``device``'s MCP client."""

        async def on_progress(progress: float, total: float | None, message: str | None) -> None:
            if self.sink is None or self.process_id is None or not math.isfinite(progress):
                return
            self.sink.send(
                {
                    "event": "progress",
                    "process_id": self.process_id,
                    "device": device,
                    "progress": progress,
                    "total": total if total is None or math.isfinite(total) else None,
                    "message": (message or None) and message[:500],
                }
            )

        return on_progress


RELAY = ProgressRelay()


def progress_from_line(event: dict[str, Any]) -> ProcessProgress | None:
    """The :class:`ProcessProgress` a ``progress`` protocol line carries, or None if malformed."""
    try:
        return ProcessProgress(
            device=str(event.get("device", "")),
            progress=float(event["progress"]),
            total=None if event.get("total") is None else float(event["total"]),
            message=event.get("message"),
            time=datetime.now(UTC),
        )
    except (KeyError, TypeError, ValueError):
        return None
