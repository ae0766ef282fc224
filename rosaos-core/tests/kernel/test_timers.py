"""TimerBook: timers in the event store fire once, as timer_fired events, and never when cancelled."""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

from rosaos.clock import LOOP_CLOCK, Clock
from rosaos.events.types import NewEvent, TimerFired
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.intake import Intake, Queued
from rosaos.kernel.loop import render_event
from rosaos.kernel.updates import UpdateStream
from rosaos.testing.manual_clock import WALL_START, ManualClock
from rosaos.timers.timer_book import MAX_WAIT_SECONDS, TimerBook, TimerError
from rosaos.timers.timer_text import DueTimeError, resolve_due

from .kernel_support import eventually


async def kernel_book(store: EventStore, clock: Clock = LOOP_CLOCK) -> TimerBook:
    """The book as the kernel opens it: firings go through the intake, published on the updates stream."""
    return await TimerBook.open(store, Intake(store, await UpdateStream.open(store.database)).submit, clock)


async def test_a_book_opened_without_the_intake_does_not_fire(store: EventStore) -> None:
    """``rosaos timers`` opens the book of a stopped kernel: it may set and cancel, never fire."""
    book = await TimerBook.open(store)
    await book.set("turn off the kitchen light", datetime.now(UTC) - timedelta(seconds=1))
    with pytest.raises(TimerError, match="only the kernel fires timers"):
        await book.fire_due()
    assert await store.pending_count() == 0


async def test_a_due_timer_queues_one_event_even_when_fired_again(store: EventStore) -> None:
    book = await kernel_book(store)
    timer = await book.set("turn off the kitchen light", datetime.now(UTC) - timedelta(seconds=1))
    [event_id] = await book.fire_due()
    assert await book.fire_due() == []
    event = await store.get(event_id)
    assert event is not None and event.kind == "timer_fired"
    assert isinstance(event.payload, TimerFired) and event.payload.timer_id == timer.id
    assert await store.pending_count() == 1
    fired = await book.get(timer.id)
    assert fired is not None and fired.state == "fired" and fired.event_id == event_id


async def test_a_crash_between_queueing_and_marking_does_not_queue_twice(store: EventStore) -> None:
    book = await kernel_book(store)
    timer = await book.set("turn off the kitchen light", datetime.now(UTC) - timedelta(seconds=1))
    [first] = await book.fire_due()
    # As if the kernel died after the append, before the row was marked fired:
    await store.database.execute("UPDATE timers SET state = 'pending' WHERE id = ?", (timer.id,))
    assert await (await kernel_book(store)).fire_due() == [first]
    assert await store.pending_count() == 1


async def test_a_cancelled_timer_never_fires_and_cannot_be_cancelled_twice(store: EventStore) -> None:
    book = await kernel_book(store)
    due = datetime.now(UTC) + timedelta(seconds=0.2)
    timer = await book.set("stop the music", due)
    await book.cancel(timer.id)
    assert await book.fire_due(now=due + timedelta(seconds=0.1)) == []  # past its time, no wait
    assert await store.pending_count() == 0
    with pytest.raises(TimerError, match="already cancelled"):
        await book.cancel(timer.id)
    with pytest.raises(KeyError):
        await book.cancel(999)


async def test_timers_survive_reopening_the_store(tmp_path: Path) -> None:
    store = await EventStore.open(tmp_path / "kernel.sqlite3")
    await (await kernel_book(store)).set("stop the music", datetime.now(UTC) + timedelta(hours=1))
    await store.close()
    reopened = await EventStore.open(tmp_path / "kernel.sqlite3")
    try:
        [timer] = await (await TimerBook.open(reopened)).pending()
        assert timer.action == "stop the music"
    finally:
        await reopened.close()


async def armed_for(clock: ManualClock, when: float) -> None:
    """Wait until the book's loop sleeps until ``when`` on ``clock`` (it has seen what changed)."""
    await eventually(lambda: clock.next_wake == when, message=f"a sleep until {when}")


async def test_the_clock_fires_a_timer_set_while_it_waits(store: EventStore) -> None:
    """On a clock the test moves: the loop wakes for a timer set while it sleeps, and fires it at its
    second, not before (no real second passes)."""
    clock = ManualClock()
    fired: list[int] = []
    rang = asyncio.Event()

    async def enqueue(event: NewEvent) -> Queued:
        appended = await store.append(event)
        fired.append(appended.id)
        rang.set()
        return Queued(appended.id, event)

    book = await TimerBook.open(store, enqueue, clock)
    loop = asyncio.create_task(book.run())
    try:
        await armed_for(clock, MAX_WAIT_SECONDS)  # asleep with nothing to do: it looks again in a minute
        await book.set("turn on the lamp", book.now() + timedelta(seconds=30))
        await armed_for(clock, 30.0)  # woken by the new timer, now asleep until it is due
        await clock.advance(29.5)
        await armed_for(clock, 30.0)
        assert not rang.is_set() and fired == []
        await clock.advance(0.5)
        async with asyncio.timeout(5):
            await rang.wait()
    finally:
        loop.cancel()
    event = await store.get(fired[0])
    assert event is not None and isinstance(event.payload, TimerFired)
    assert event.payload.due == datetime.fromtimestamp(WALL_START + 30, UTC)
    assert render_event(event).startswith("[Timer fired] timer=1 due=")
    assert "late" not in render_event(event)


async def test_a_timer_ten_minutes_off_fires_at_the_tenth_minute_not_before(store: EventStore) -> None:
    """The loop looks again every minute (a timer another process added is seen) and fires nothing
    early; ten minutes pass on the test's clock in no time."""
    clock = ManualClock()
    book = await kernel_book(store, clock)
    await book.set("turn off the kitchen light", book.now() + timedelta(minutes=10))
    loop = asyncio.create_task(book.run())
    try:
        for minute in range(1, 10):
            await armed_for(clock, minute * MAX_WAIT_SECONDS)
            await clock.advance(MAX_WAIT_SECONDS)
        await armed_for(clock, 600.0)  # it looked at 9 minutes: nothing due, so it waits for the timer
        assert await store.pending_count() == 0
        await clock.advance(MAX_WAIT_SECONDS)
        await eventually(lambda: _one_pending(store), message="the timer's event")
    finally:
        loop.cancel()
    [timer] = await book.list_timers(include_settled=True)
    assert timer.state == "fired" and timer.settled_at == datetime.fromtimestamp(WALL_START + 600, UTC)


async def _one_pending(store: EventStore) -> bool:
    return await store.pending_count() == 1


async def test_a_late_timer_says_how_late(store: EventStore) -> None:
    book = await kernel_book(store)
    await book.set("turn on the lamp", datetime.now(UTC) - timedelta(minutes=90))
    [event_id] = await book.fire_due()
    event = await store.get(event_id)
    assert event is not None
    assert "(late by 1 h 30 min: the kernel was not running then)" in render_event(event)
    assert render_event(event).endswith("\naction: turn on the lamp")


def test_clock_times_resolve_to_the_next_local_moment() -> None:
    now = datetime(2026, 11, 25, 22, 0).astimezone()
    assert resolve_due(None, "23:00", now) == now.replace(hour=23)
    assert resolve_due(None, "07:30", now) == (now + timedelta(days=1)).replace(hour=7, minute=30)
    assert resolve_due(600, None, now) == now + timedelta(minutes=10)
    for bad in [(None, None), (5, "23:00"), (None, "25:00"), (None, "soon"), (None, "2020-01-01T10:00")]:
        with pytest.raises(DueTimeError):
            resolve_due(*bad, now)  # type: ignore[arg-type]
