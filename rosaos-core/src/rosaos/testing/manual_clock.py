"""A clock for tests: time moves only when the test says so.

Give it to anything that takes a :class:`rosaos.clock.Clock` (the device state cache, ...).
Code under test that sleeps on it waits until the test calls :meth:`ManualClock.advance` past its
wake-up time; nothing waits on real time, so a busy computer cannot make the test late.
"""

from __future__ import annotations

import asyncio


class ManualClock:
    """A :class:`rosaos.clock.Clock` whose time the test advances."""

    def __init__(self, start: float = 0.0) -> None:
        self._now = start
        self._sleepers: list[tuple[float, asyncio.Future[None]]] = []

    def now(self) -> float:
        return self._now

    @property
    def sleeping(self) -> int:
        """How many sleeps are waiting for time to move (a test waits for the code to get there)."""
        return sum(1 for _, future in self._sleepers if not future.done())

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
