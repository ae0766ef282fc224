"""The test clock: monotonic and wall time move together and only when the test says; a sleep on
it ends when time passes or, with ``sleep_unless``, when it is woken first."""

from __future__ import annotations

import asyncio
import time

import pytest

from rosaos.clock import LOOP_CLOCK, sleep_unless
from rosaos.testing.manual_clock import WALL_START, ManualClock


async def test_wall_time_moves_with_the_clock_and_only_forward() -> None:
    clock = ManualClock(start=5.0)
    assert (clock.now(), clock.wall()) == (5.0, WALL_START)
    await clock.advance(600)
    assert (clock.now(), clock.wall()) == (605.0, WALL_START + 600)
    with pytest.raises(ValueError, match="only moves forward"):
        await clock.advance(-1)


async def test_the_loop_clock_tells_the_wall_time() -> None:
    before = time.time()
    assert before <= LOOP_CLOCK.wall() <= time.time()


async def settled() -> None:
    """Let the tasks just created take their steps (no real time passes)."""
    for _ in range(10):
        await asyncio.sleep(0)


async def test_a_sleep_ends_when_its_time_comes_unless_woken_first() -> None:
    clock = ManualClock()
    woken = asyncio.Event()
    slept = asyncio.create_task(sleep_unless(clock, 60, woken))
    await settled()
    assert clock.next_wake == 60
    await clock.advance(60)
    assert await slept is False and clock.next_wake is None

    waiting = asyncio.create_task(sleep_unless(clock, 60, woken))
    await settled()
    assert clock.next_wake == 120
    woken.set()
    assert await waiting is True
    assert clock.next_wake is None and clock.sleeping == 0  # the clock's sleep was let go
    assert await sleep_unless(clock, 60, woken) is True  # already set: no sleep at all
