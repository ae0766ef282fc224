"""The time a waiting loop waits on, passed in (the device state cache today; the timer clock and
the health checks are the next candidates).

Production code uses :data:`LOOP_CLOCK`: the event loop's monotonic time and ``asyncio.sleep``,
exactly what the code called before the clock was injectable. Tests pass a
:class:`rosaos.testing.manual_clock.ManualClock` instead and move time themselves: a test of a 10-second
watch window then takes no seconds, and it cannot fail because a busy computer was slow to wake
a sleeper, only because the code did the wrong thing.
"""

from __future__ import annotations

import asyncio
from typing import Protocol


class Clock(Protocol):
    """Monotonic seconds and a sleep measured in them."""

    def now(self) -> float:
        """Seconds on a monotonic scale (only differences mean anything)."""
        ...

    async def sleep(self, seconds: float) -> None:
        """Return once ``seconds`` have passed on this clock."""
        ...


class LoopClock:
    """The running event loop's clock (``loop.time()``) and ``asyncio.sleep``."""

    def now(self) -> float:
        return asyncio.get_running_loop().time()

    async def sleep(self, seconds: float) -> None:
        await asyncio.sleep(seconds)


LOOP_CLOCK = LoopClock()
"""The clock every production caller uses."""
