"""Durable timers: "turn off the light in ten minutes", kept in the kernel's event store.

A timer is a row in the ``timers`` table of the same SQLite file as the events, so it survives
a restart (and a ``kill -9``). :class:`TimerBook` fires a due timer by queueing a
``timer_fired`` event with the idempotency key ``timer-<id>`` (through the kernel's intake,
:mod:`rosaos.kernel.intake`) and only then marking the row fired. A crash between the two leaves the row pending; the next start appends again, the key
answers the first event's id, and nothing is queued twice: a timer fires exactly once. The
kernel handles that event like a command (its action becomes a process). A timer that fell due
while the kernel was down fires once at start-up, and its event says how late it is.
"""

from __future__ import annotations

import asyncio
import logging
import sqlite3
from collections.abc import Awaitable, Callable
from datetime import UTC, datetime, timedelta
from typing import Any, Literal

from pydantic import BaseModel, Field

from rosaos.clock import LOOP_CLOCK, Clock, sleep_unless
from rosaos.events.types import NewEvent, TimerFired, TimerFiredEvent
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.intake import Queued

log = logging.getLogger(__name__)

TimerState = Literal["pending", "fired", "cancelled"]
MAX_DELAY = timedelta(days=366)
"""A timer further off than this is refused: almost surely a misheard date."""
MAX_WAIT_SECONDS = 60.0
"""The clock re-reads the table at least this often (a timer added by another process is seen)."""
RECENT_LIMIT = 50

_SCHEMA = """
CREATE TABLE IF NOT EXISTS timers (
    id INTEGER PRIMARY KEY AUTOINCREMENT,  -- never reused, so "timer 3" always means one timer
    created REAL NOT NULL,
    due REAL NOT NULL,
    action TEXT NOT NULL,
    state TEXT NOT NULL DEFAULT 'pending',
    settled_at REAL,                       -- when it fired or was cancelled
    event_id INTEGER                       -- the timer_fired event it queued
);
CREATE INDEX IF NOT EXISTS timers_pending ON timers (due) WHERE state = 'pending';
"""
_COLUMNS = "id, created, due, action, state, settled_at, event_id"


class Timer(BaseModel):
    """One timer: what it will do, when, and whether it has fired or been cancelled."""

    id: int = Field(description="Never reused; the id to cancel it by.")
    action: str = Field(description="What the kernel does when it fires, as a command.")
    due: datetime = Field(description="When it fires (UTC).")
    created: datetime = Field(description="When it was set (UTC).")
    state: TimerState = Field(description="pending, fired or cancelled.")
    settled_at: datetime | None = Field(default=None, description="When it fired or was cancelled.")
    event_id: int | None = Field(default=None, description="The timer_fired event it queued.")


class TimerList(BaseModel):
    """The answer of ``GET /timers``: pending timers, soonest first (with ``all``, recent others too)."""

    timers: list[Timer]
    now: datetime = Field(description="The kernel's clock (UTC), to count down from.")


class TimerError(ValueError):
    """A timer that cannot be set or cancelled; the message says why and what to do."""


Enqueue = Callable[[NewEvent], Awaitable[Queued]]
"""How a firing is queued: the kernel's :meth:`~rosaos.kernel.intake.Intake.submit`."""


class TimerBook:
    """The kernel's timers: set, list, cancel, and fire them when due (:meth:`run`).

    ``enqueue`` queues a firing: the running kernel passes its intake, the one way into the
    queue. A book opened without it (``rosaos timers`` on the store of a stopped kernel) sets,
    lists and cancels, but does not fire. All access goes through one lock, so a cancel and a
    firing never cross. Time is ``clock``'s wall time (tests pass a
    :class:`~rosaos.testing.manual_clock.ManualClock` and move it: ten minutes in no time).
    """

    def __init__(self, store: EventStore, enqueue: Enqueue | None = None, clock: Clock = LOOP_CLOCK) -> None:
        self._database = store.database
        self._enqueue = enqueue
        self._clock = clock
        self._lock = asyncio.Lock()
        self._changed = asyncio.Event()

    @classmethod
    async def open(
        cls, store: EventStore, enqueue: Enqueue | None = None, clock: Clock = LOOP_CLOCK
    ) -> TimerBook:
        """Create the table if needed; the book shares the event store's connection and thread."""
        await store.database.executescript(_SCHEMA)
        return cls(store, enqueue, clock)

    def now(self) -> datetime:
        """The book's time, as an aware UTC datetime (what due times are counted from)."""
        return datetime.fromtimestamp(self._clock.wall(), UTC)

    async def set(self, action: str, due: datetime) -> Timer:
        """Add a timer that runs ``action`` at ``due`` (aware datetime). Raises :class:`TimerError`."""
        action = " ".join(action.split())
        if not action:
            raise TimerError("a timer needs an action, e.g. 'turn off the kitchen light'")
        if due.tzinfo is None:
            raise TimerError("the due time needs a time zone")
        now = self._clock.wall()
        if due.timestamp() - now > MAX_DELAY.total_seconds():
            raise TimerError(f"{due.isoformat()} is more than a year away; set a nearer time")
        async with self._lock:
            rows = await self._database.run(
                lambda connection: connection.execute(
                    f"INSERT INTO timers (created, due, action) VALUES (?, ?, ?) RETURNING {_COLUMNS}",
                    (now, due.timestamp(), action),
                ).fetchall()
            )
        self._changed.set()
        return _timer(rows[0])

    async def get(self, timer_id: int) -> Timer | None:
        """The timer with this id, whatever its state, or None."""
        rows = await self._database.fetch(f"SELECT {_COLUMNS} FROM timers WHERE id = ?", (timer_id,))
        return _timer(rows[0]) if rows else None

    async def pending(self) -> list[Timer]:
        """The timers still to fire, soonest first."""
        rows = await self._database.fetch(
            f"SELECT {_COLUMNS} FROM timers WHERE state = 'pending' ORDER BY due, id"
        )
        return [_timer(row) for row in rows]

    async def list_timers(self, include_settled: bool = False) -> list[Timer]:
        """Pending timers; with ``include_settled``, also the last fired or cancelled ones."""
        timers = await self.pending()
        if include_settled:
            rows = await self._database.fetch(
                f"SELECT {_COLUMNS} FROM timers WHERE state != 'pending' ORDER BY settled_at DESC LIMIT ?",
                (RECENT_LIMIT,),
            )
            timers += [_timer(row) for row in rows]
        return timers

    async def cancel(self, timer_id: int) -> Timer:
        """Cancel a pending timer. ``KeyError`` for an unknown id, :class:`TimerError` if it is settled."""
        async with self._lock:

            def settle(connection: sqlite3.Connection) -> list[tuple[Any, ...]]:
                return connection.execute(
                    "UPDATE timers SET state = 'cancelled', settled_at = ? "
                    f"WHERE id = ? AND state = 'pending' RETURNING {_COLUMNS}",
                    (self._clock.wall(), timer_id),
                ).fetchall()

            rows = await self._database.run(settle)
        if rows:
            self._changed.set()
            return _timer(rows[0])
        timer = await self.get(timer_id)
        if timer is None:
            raise KeyError(f"no timer {timer_id}")
        done = "has already fired" if timer.state == "fired" else "was already cancelled"
        raise TimerError(f"timer {timer_id} {done}; nothing to cancel")

    async def fire_due(self, now: datetime | None = None) -> list[int]:
        """Queue a ``timer_fired`` event for every pending timer due by ``now``; return the event ids."""
        if self._enqueue is None:
            raise TimerError(
                "this timer book was opened without the kernel's intake: only the kernel fires timers"
            )
        enqueue = self._enqueue
        moment = (now or self.now()).timestamp()
        fired: list[int] = []
        async with self._lock:
            rows = await self._database.fetch(
                f"SELECT {_COLUMNS} FROM timers WHERE state = 'pending' AND due <= ? ORDER BY due, id",
                (moment,),
            )
            for row in rows:
                timer = _timer(row)
                event = fired_event(timer, datetime.fromtimestamp(moment, UTC))
                # The key makes this safe to repeat: a crash before the UPDATE below re-appends
                # at the next start and gets the first event's id back.
                queued = await enqueue(event)
                await self._database.execute(
                    "UPDATE timers SET state = 'fired', settled_at = ?, event_id = ? WHERE id = ?",
                    (moment, queued.id, timer.id),
                )
                fired.append(queued.id)
        return fired

    async def seconds_to_next(self) -> float | None:
        """Seconds until the soonest pending timer (0 if overdue), or None when there is none."""
        rows = await self._database.fetch("SELECT min(due) FROM timers WHERE state = 'pending'")
        due = rows[0][0]
        return None if due is None else max(0.0, float(due) - self._clock.wall())

    async def run(self) -> None:
        """Fire timers as they fall due, for as long as the kernel runs (cancel the task to stop)."""
        while True:
            self._changed.clear()
            try:
                await self.fire_due()
            except Exception:  # a disk error must not stop every later timer: log, retry soon
                log.exception("firing due timers failed; retrying in 1 s")
                await self._clock.sleep(1.0)
                continue
            wait = await self.seconds_to_next()
            wait = MAX_WAIT_SECONDS if wait is None else min(wait, MAX_WAIT_SECONDS)
            # Woken early when a timer is set or cancelled; the soonest may have changed.
            await sleep_unless(self._clock, max(wait, 0.01), self._changed)


def fired_event(timer: Timer, now: datetime) -> TimerFiredEvent:
    """The event a timer queues when it fires at ``now``."""
    late = max(0.0, (now - timer.due).total_seconds())
    return TimerFiredEvent(
        kind="timer_fired",
        source="timers",
        idempotency_key=f"timer-{timer.id}",
        payload=TimerFired(
            timer_id=timer.id, action=timer.action, due=timer.due, late_seconds=round(late, 1)
        ),
    )


def _timer(row: tuple[Any, ...]) -> Timer:
    timer_id, created, due, action, state, settled_at, event_id = row
    return Timer(
        id=timer_id,
        action=action,
        due=datetime.fromtimestamp(due, UTC),
        created=datetime.fromtimestamp(created, UTC),
        state=state,
        settled_at=None if settled_at is None else datetime.fromtimestamp(settled_at, UTC),
        event_id=event_id,
    )
