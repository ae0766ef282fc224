"""Which event, and which launch within its handling, a ``launch_process`` call comes from.

The kernel loop handles one event at a time. Each launch it makes is named by ``(event id, step)``,
step counting the launches made while handling that event (0, 1, …). The kernel records that
cause durably *before* a worker is told to start (:mod:`rosaos.kernel.orphans`). After a crash the
event is handled again; the launch with the same cause is then refused, because its first run is
already accounted for as an orphan: a command never runs twice.

A plain object rather than a context variable: the kernel's tools run in the task of their
in-process MCP session, not in the task of the event being handled.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class LaunchCause:
    """The event a launch was made for, and its place among that event's launches."""

    event_id: int
    step: int


class CurrentEvent:
    """The event the kernel loop is handling now, and how many launches it has made so far."""

    def __init__(self) -> None:
        self.event_id: int | None = None
        self.said: str | None = None
        """The user's sentence when the turn holds exactly one (``launch_process``'s default task)."""
        self._steps = 0

    def begin(self, event_id: int, said: str | None = None) -> None:
        self.event_id, self.said, self._steps = event_id, said, 0

    def end(self) -> None:
        self.event_id, self.said = None, None

    def next_cause(self) -> LaunchCause | None:
        """The cause of the launch being made now; None outside the handling of an event."""
        if self.event_id is None:
            return None
        cause = LaunchCause(self.event_id, self._steps)
        self._steps += 1
        return cause
