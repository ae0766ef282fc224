"""The device state poller reads devices only while someone looks, and never serves a stale state."""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from typing import Any

import pytest
from devices_support import eventually
from fastmcp import FastMCP

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.devices.serve import serve_http
from rosaos.devices.state_cache import DeviceStateCache

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


@pytest.fixture
async def served() -> AsyncIterator[tuple[Counter, DeviceStateCache]]:
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
        cache = DeviceStateCache(lambda: {"counter": endpoint}, interval=0.05, watch=0.3)
        task = asyncio.create_task(cache.run())
        try:
            yield counter, cache
        finally:
            task.cancel()
            await asyncio.gather(task, return_exceptions=True)


async def test_nobody_looking_means_no_reads_after_the_first(
    served: tuple[Counter, DeviceStateCache],
) -> None:
    counter, cache = served
    await eventually(lambda: cache.get("counter") is not None, within=10)
    await asyncio.sleep(0.5)  # ten intervals with nobody looking
    assert counter.reads == 1


async def test_looking_keeps_it_polling_for_the_watch_window_then_it_stops(
    served: tuple[Counter, DeviceStateCache],
) -> None:
    counter, cache = served
    await cache.wanted()
    await eventually(lambda: counter.reads >= 4, within=10)  # it polls on its own while wanted
    await asyncio.sleep(cache.watch + 0.2)  # the window ends
    settled = counter.reads
    await asyncio.sleep(0.5)
    assert counter.reads == settled


async def test_a_look_after_a_quiet_spell_waits_for_a_fresh_state(
    served: tuple[Counter, DeviceStateCache],
) -> None:
    counter, cache = served
    await asyncio.sleep(0.5)  # idle: the cached state is stale now
    before = counter.reads
    await cache.wanted()
    state = cache.get("counter")
    assert state is not None and state["reads"] > before
