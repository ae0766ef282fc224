"""The time a waiting loop waits on, passed in: the device state cache, the timers, the health
checks of remote devices.

Production code uses :data:`LOOP_CLOCK`: the event loop's monotonic time and ``asyncio.sleep``,
exactly what the code called before the clock was injectable. Tests pass a
:class:`rosaos.testing.manual_clock.ManualClock` instead and move time themselves: a test of a 10-second
watch window then takes no seconds, and it cannot fail because a busy computer was slow to wake
a sleeper, only because the code did the wrong thing.
"""

from __future__ import annotations

import asyncio
import time
from typing import Protocol


class Clock(Protocol):
    """Monotonic seconds and a sleep measured in them, and the wall time on the same scale."""

    def now(self) -> float:
        """Seconds on a monotonic scale (only differences mean anything)."""
        ...

    def wall(self) -> float:
        """Seconds since the Unix epoch (UTC): what a timer's due time is written in."""
        ...

    async def sleep(self, seconds: float) -> None:
        """Return once ``seconds`` have passed on this clock."""
        ...


class LoopClock:
    """The running event loop's clock (``loop.time()``) and ``asyncio.sleep``."""

    def now(self) -> float:
        return asyncio.get_running_loop().time()

    def wall(self) -> float:
        return time.time()

    async def sleep(self, seconds: float) -> None:
        await asyncio.sleep(seconds)


async def sleep_unless(clock: Clock, seconds: float, woken: asyncio.Event) -> bool:
    """Sleep ``seconds`` on ``clock``, or less if ``woken`` is set first; True if it was."""
    if woken.is_set():
        return True
    sleeper = asyncio.ensure_future(clock.sleep(seconds))
    waker = asyncio.ensure_future(woken.wait())
    try:
        await asyncio.wait({sleeper, waker}, return_when=asyncio.FIRST_COMPLETED)
    finally:
        for task in (sleeper, waker):
            task.cancel()
        await asyncio.gather(sleeper, waker, return_exceptions=True)
    return woken.is_set()


LOOP_CLOCK = LoopClock()
"""The clock every production caller uses."""
