"""A clock for tests: time moves only when the test says so.

Give it to anything that takes a :class:`rosaos.clock.Clock` (the device state cache, ...).
Code under test that sleeps on it waits until the test calls :meth:`ManualClock.advance` past its
wake-up time; nothing waits on real time, so a busy computer cannot make the test late.
"""

from __future__ import annotations

import asyncio

WALL_START = 1_795_000_000.0
"""The wall time a manual clock starts at unless told (2026-11-18 08:26:40 UTC): fixed, so a
test's timers fall at the same instants every run."""


class ManualClock:
    """A :class:`rosaos.clock.Clock` whose time the test advances (its wall time moves with it)."""

    def __init__(self, start: float = 0.0, wall: float = WALL_START) -> None:
        self._now = start
        self._wall_offset = wall - start
        self._sleepers: list[tuple[float, asyncio.Future[None]]] = []

    def now(self) -> float:
        return self._now

    def wall(self) -> float:
        return self._now + self._wall_offset

    @property
    def sleeping(self) -> int:
        """How many sleeps are waiting for time to move (a test waits for the code to get there)."""
        return sum(1 for _, future in self._sleepers if not future.done())

    @property
    def next_wake(self) -> float | None:
        """When the earliest waiting sleep wakes, on this clock (None: nothing sleeps). A test waits
        for this to know the code has armed its wait, e.g. for a timer it was just told of."""
        return min((due for due, future in self._sleepers if not future.done()), default=None)

    async def sleep(self, seconds: float) -> None:
        if seconds <= 0:
            await asyncio.sleep(0)
            return
        future: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        entry = (self._now + seconds, future)
        self._sleepers.append(entry)
        try:
            await future
        finally:
            if entry in self._sleepers:
                self._sleepers.remove(entry)

    async def advance(self, seconds: float) -> None:
        """Move time forward by ``seconds`` and wake every sleep that is due by then."""
        if seconds < 0:
            raise ValueError(f"a clock only moves forward; advance({seconds}) would move it back")
        self._now += seconds
        due = [entry for entry in self._sleepers if entry[0] <= self._now]
        for entry in due:
            self._sleepers.remove(entry)
            if not entry[1].done():
                entry[1].set_result(None)
        await asyncio.sleep(0)  # let the woken sleepers take their next step
