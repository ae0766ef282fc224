"""Live device state for the kernel's ``GET /devices`` and the web page's device cards.

One poller reads every served device's ``get_state`` about once a second over a kept-open MCP
session, so any number of open pages cost the devices nothing extra. It polls only while someone
looks: each ``GET /devices`` (:meth:`DeviceStateCache.wanted`) keeps it going for ``watch``
seconds, and an idle ``rosaos up`` with no page open reads nothing. A request after a quiet
spell waits for one fresh read rather than show a stale state.

At most ``concurrency`` devices are read at once: opening a hundred MCP sessions together on a
busy machine makes every one of them miss its timeout, and then nothing is ever shown. The
timeout counts from a read's own start, not from its wait for a turn.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable, Mapping
from typing import Any

from rosaos.clock import LOOP_CLOCK, Clock
from rosaos.devices.client import DeviceClient
from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.drivers import DeviceError

log = logging.getLogger(__name__)


class DeviceStateCache:
    """The last ``get_state`` of every reachable device, refreshed in the background."""

    def __init__(
        self,
        endpoints: Callable[[], Mapping[str, DeviceEndpoint]],
        interval: float = 1.0,
        timeout: float = 3.0,
        watch: float = 10.0,
        concurrency: int = 8,
        clock: Clock = LOOP_CLOCK,
    ) -> None:
        self._endpoints = endpoints
        self._clock = clock
        self.interval = interval
        self.timeout = timeout
        self.watch = watch
        """Seconds of polling that one :meth:`wanted` buys."""
        self._states: dict[str, dict[str, Any]] = {}
        self._clients: dict[str, tuple[str, DeviceClient]] = {}
        self._wanted_until = 0.0
        self._refreshed_at = float("-inf")
        self._wake = asyncio.Event()
        self._lock = asyncio.Lock()
        self._turns = asyncio.Semaphore(concurrency)
        self.refreshes = 0
        """How many times every device was read (for tests and benchmarks)."""

    def get(self, name: str) -> dict[str, Any] | None:
        """The last state read from ``name``, or None if it has not answered yet."""
        return self._states.get(name)

    async def wanted(self) -> None:
        """Someone is looking: poll for the next ``watch`` seconds. Returns once the states are
        no older than two intervals (at once while polling; after one read after a quiet spell)."""
        self._wanted_until = self._clock.now() + self.watch
        self._wake.set()
        if self._clock.now() - self._refreshed_at > 2 * self.interval:
            await self.refresh()

    async def refresh(self) -> None:
        """Read every served device's state once, all at the same time."""
        async with self._lock:
            endpoints = {n: e for n, e in self._endpoints().items() if e.url is not None}
            await asyncio.gather(*(self._read(endpoint) for endpoint in endpoints.values()))
            for gone in set(self._states) - set(endpoints):
                self._states.pop(gone, None)
            self._refreshed_at = self._clock.now()
            self.refreshes += 1

    async def run(self) -> None:
        """Refresh while wanted, sleep while not, until cancelled; then close the sessions."""
        try:
            await self.refresh()  # one read at start, so the first page load is instant
            while True:
                self._wake.clear()
                if self._clock.now() < self._wanted_until:
                    await self._clock.sleep(self.interval)
                else:
                    await self._wake.wait()
                if self._clock.now() - self._refreshed_at >= self.interval / 2:
                    await self.refresh()
        finally:
            for _, client in self._clients.values():
                with contextlib.suppress(Exception):
                    await client.__aexit__(None, None, None)
            self._clients.clear()

    async def _read(self, endpoint: DeviceEndpoint) -> None:
        async with self._turns:
            await self._read_now(endpoint)

    async def _read_now(self, endpoint: DeviceEndpoint) -> None:
        assert endpoint.url is not None
        try:
            client = await self._client(endpoint)
            self._states[endpoint.name] = await asyncio.wait_for(client.get_state(), self.timeout)
        except (DeviceError, TimeoutError) as error:
            log.debug("%s: state not read: %s", endpoint.name, error)
            self._states.pop(endpoint.name, None)
            await self._drop(endpoint.name)

    async def _client(self, endpoint: DeviceEndpoint) -> DeviceClient:
        assert endpoint.url is not None
        known = self._clients.get(endpoint.name)
        if known is not None and known[0] == endpoint.url:
            return known[1]
        await self._drop(endpoint.name)
        client = DeviceClient(endpoint.url, endpoint.token, self.timeout, endpoint.name)
        await client.__aenter__()
        self._clients[endpoint.name] = (endpoint.url, client)
        return client

    async def _drop(self, name: str) -> None:
        known = self._clients.pop(name, None)
        if known is not None:
            with contextlib.suppress(Exception):
                await known[1].__aexit__(None, None, None)
