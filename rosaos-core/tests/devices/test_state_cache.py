"""The device state poller reads devices only while someone looks, and never serves a stale state.

The poller runs on a clock the test moves (:class:`rosaos.testing.manual_clock.ManualClock`), so the
watch window and the intervals are the production ones and no test sleeps through them."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import Any

import pytest
from fastmcp import FastMCP

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.devices.serve import serve_http
from rosaos.devices.state_cache import DeviceStateCache
from rosaos.testing.manual_clock import ManualClock

from .devices_support import eventually

TOKEN = "state-cache-token"


class Counter:
    """A device whose state is how many times it was read."""

    def __init__(self) -> None:
        self.reads = 0
        self.server = FastMCP("counter")

        @self.server.tool(annotations={"readOnlyHint": True})
        def get_state() -> dict[str, Any]:
            """How many times the state was read."""
            self.reads += 1
            return {"reads": self.reads}


INTERVAL = 1.0
WATCH = 10.0


@dataclass
class Served:
    counter: Counter
    cache: DeviceStateCache
    clock: ManualClock

    async def tick(self) -> None:
        """One polling interval passes, once the poller is asleep waiting for it."""
        await eventually(lambda: self.clock.sleeping == 1, within=10)
        await self.clock.advance(INTERVAL)


@pytest.fixture
async def served() -> AsyncIterator[Served]:
    """A counter served on loopback and a cache polling it on a clock the test moves (the
    production interval and watch window: no test waits on them)."""
    counter = Counter()
    async with serve_http(counter.server, TOKEN) as device:
        endpoint = DeviceEndpoint(
            name="counter",
            driver="test",
            concurrency="shared",
            always_attached=False,
            description="counts its reads",
            prompt="-",
            url=device.url,
            token=TOKEN,
            status="healthy",
        )
        clock = ManualClock()
        cache = DeviceStateCache(lambda: {"counter": endpoint}, interval=INTERVAL, watch=WATCH, clock=clock)
        task = asyncio.create_task(cache.run())
        try:
            yield Served(counter, cache, clock)
        finally:
            task.cancel()
            await asyncio.gather(task, return_exceptions=True)


async def test_nobody_looking_means_no_reads_after_the_first(served: Served) -> None:
    await eventually(lambda: served.cache.get("counter") is not None, within=10)
    for _ in range(10):  # ten intervals with nobody looking
        await served.clock.advance(INTERVAL)
        await asyncio.sleep(0.01)
    assert served.clock.sleeping == 0, "nobody looks: the poller waits to be wanted, not on a timer"
    assert served.counter.reads == 1


async def test_looking_keeps_it_polling_for_the_watch_window_then_it_stops(served: Served) -> None:
    counter, cache = served.counter, served.cache
    await eventually(lambda: cache.refreshes == 1, within=10)  # the read at start, stored
    await cache.wanted()
    for reads in range(2, int(WATCH / INTERVAL) + 2):  # it polls on its own, once an interval
        await served.tick()
        await eventually(lambda: counter.reads == reads, within=10)  # noqa: B023 - awaited at once
    # The window has ended: the poller waits to be wanted again, whatever time passes.
    await eventually(lambda: served.clock.sleeping == 0, within=10)
    settled = counter.reads
    for _ in range(5):
        await served.clock.advance(INTERVAL)
        await asyncio.sleep(0.01)
    assert counter.reads == settled == 1 + WATCH / INTERVAL


async def test_a_look_after_a_quiet_spell_waits_for_a_fresh_state(served: Served) -> None:
    counter, cache = served.counter, served.cache
    await eventually(lambda: cache.refreshes == 1, within=10)  # the read at start, stored
    await served.clock.advance(5 * INTERVAL)  # idle: the cached state is stale now
    before = counter.reads
    await cache.wanted()
    state = cache.get("counter")
    assert state is not None and state["reads"] > before


async def test_a_look_while_the_state_is_fresh_answers_at_once(served: Served) -> None:
    counter, cache = served.counter, served.cache
    await eventually(lambda: cache.refreshes == 1, within=10)  # the read at start, stored
    await served.clock.advance(INTERVAL)  # younger than two intervals
    await cache.wanted()
    assert cache.get("counter") == {"reads": 1}, "no read was waited for"
    await eventually(lambda: counter.reads == 2, within=10)  # the poller, woken, reads in the background
