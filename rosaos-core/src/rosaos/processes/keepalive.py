"""The worker's half of the device deadman: keepalives, and a deadline on every device call.

While a job runs, the worker posts ``/keepalive`` to each granted device host every
:data:`~rosaos.devices.deadman.KEEPALIVE_INTERVAL` s under its owner name (the host stops an
armed device after :data:`~rosaos.devices.deadman.SILENCE_LIMIT` s of silence, see
:mod:`rosaos.devices.deadman`). The same link tells the worker when a device went quiet, so a
call on a silent link does not hold its lease until the job timeout:

- every call has a **deadline** derived from what it asked for (seconds, or distance / speed, or
  angle / speed, times :data:`MARGIN`, at least :data:`FLOOR`); past it, a call whose device does
  not answer keepalives fails, saying the device is unreachable;
- a call during which the link was lost for longer than the silence limit and came back fails at
  once: the host's deadman has stopped what it was doing, and its answer may never arrive;
- a call the host reports as stopped by its deadman fails at once with that reason.

When the job ends its owner name is released at each host, so an idle warm worker owes nothing.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import os
import secrets
import time
from collections.abc import AsyncIterator, Sequence
from dataclasses import dataclass, field
from typing import Any

import httpx
from pydantic_ai import RunContext
from pydantic_ai.exceptions import ToolFailed
from pydantic_ai.toolsets import ToolsetTool, WrapperToolset

from rosaos.devices.deadman import KEEPALIVE_INTERVAL, KEEPALIVE_PATH, OWNER_HEADER, SILENCE_LIMIT
from rosaos.processes.jobs import GrantedDevice
from rosaos.tls import shared_context

log = logging.getLogger("rosaos.processes.keepalive")

OWNER = f"worker-{os.getpid()}-{secrets.token_hex(4)}"
"""This worker's owner name at the device hosts (sent on every MCP request and keepalive)."""
MARGIN = 2.0
"""A call may take this many times what it asked for before a silent device fails it."""
FLOOR = 5.0
"""Seconds every call gets at least (connect, a state read, a slow host)."""
SLOWEST_LINEAR = 0.1
"""m/s assumed when a distance comes without a speed (drivers default to faster)."""
SLOWEST_ANGULAR = 0.3
"""rad/s assumed when an angle comes without a speed."""
SECONDS_ARGS = ("duration", "seconds", "timeout", "max_seconds")
DISTANCE_ARGS = ("meters", "distance", "max_distance_m", "distance_m")
CHECK_PERIOD = 0.1


def owner_headers() -> dict[str, str]:
    """The header every request of this worker to a device carries."""
    return {OWNER_HEADER: OWNER}


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        return None
    return abs(float(value))


def call_deadline(args: dict[str, Any]) -> float:
    """Seconds a call with ``args`` may take before a silent device fails it: asked-for time × margin."""
    asked = sum(seconds for name in SECONDS_ARGS if (seconds := _number(args.get(name))) is not None)
    speed = _number(args.get("speed"))
    for name in DISTANCE_ARGS:
        if (meters := _number(args.get(name))) is not None:
            asked += meters / (speed if speed else SLOWEST_LINEAR)
    for name, to_radians in (("degrees", math.radians), ("radians", float)):
        if (angle := _number(args.get(name))) is not None:
            asked += to_radians(angle) / (speed if speed else SLOWEST_ANGULAR)
    return max(FLOOR, asked * MARGIN)


def keepalive_url(mcp_url: str) -> str:
    """``http://host:port/mcp`` → ``http://host:port/keepalive``."""
    base = mcp_url.rstrip("/")
    base = base.removesuffix("/mcp")
    return base + KEEPALIVE_PATH


@dataclass
class DeviceLink:
    """Keepalives to one device host, and what they say about the link."""

    device: GrantedDevice
    last_answer: float = field(default_factory=time.monotonic)
    stopped: int = 0
    """How many times the host says its deadman stopped the device for this worker."""
    losses: list[tuple[float, float]] = field(default_factory=list)
    """(lost at, back at) for every silence longer than the host's limit."""
    _task: asyncio.Task[None] | None = None

    def quiet_for(self) -> float:
        """Seconds since the host last answered a keepalive."""
        return time.monotonic() - self.last_answer

    def lost_and_back_since(self, since: float) -> tuple[float, float] | None:
        """A loss longer than the host's silence limit that ended after ``since``, if any."""
        return next((loss for loss in self.losses if loss[1] >= since), None)

    async def run(self) -> None:
        url = keepalive_url(self.device.url)
        headers = {**owner_headers(), "Authorization": f"Bearer {self.device.token}"}
        while True:
            http = CLIENTS.get(url)
            while True:
                sent = time.monotonic()
                try:
                    response = await http.post(url, headers=headers)
                    answer = response.json() if response.is_success else {}
                except (httpx.HTTPError, ValueError):
                    break
                self._answered(answer)
                await asyncio.sleep(max(0.0, KEEPALIVE_INTERVAL - (time.monotonic() - sent)))
            # A fresh client after each failure: a connection into a silent network stays stuck.
            await CLIENTS.drop(url, http)
            await asyncio.sleep(0.05)

    def _answered(self, answer: dict[str, Any]) -> None:
        now = time.monotonic()
        if now - self.last_answer > SILENCE_LIMIT:
            self.losses.append((self.last_answer, now))
            log.warning(
                "device %s: link back after %.1f s of silence", self.device.name, now - self.last_answer
            )
        self.last_answer = now
        stopped = answer.get("stopped")
        if isinstance(stopped, int):
            self.stopped = stopped

    async def release(self) -> None:
        """Tell the host this worker's job ended (best effort: a silent host disarms by itself)."""
        headers = {**owner_headers(), "Authorization": f"Bearer {self.device.token}"}
        url = keepalive_url(self.device.url)
        http = CLIENTS.get(url)
        try:
            await http.post(url, headers=headers, params={"release": "1"})
        except httpx.HTTPError:
            await CLIENTS.drop(url, http)


class KeptClients:
    """One HTTP client per device host for this worker's keepalives, kept from job to job.

    A client per job cost the worker about half a millisecond of CPU to build, and the host a new
    connection, right beside the job's first device call (and again for the release): a third of
    a light switch's worker time on 2 cores (issue 26, part 8). When they are sent is unchanged:
    the first keepalive still goes at once. A client that failed is closed and dropped, so the
    next attempt opens a fresh connection (one into a silent network stays stuck); an idle
    connection is dropped by the client after :data:`KEPT_IDLE` s, before the host's server
    closes it (uvicorn: 5 s), so a job seldom starts on a connection the host just closed.
    """

    def __init__(self) -> None:
        self._clients: dict[str, httpx.AsyncClient] = {}

    def get(self, url: str) -> httpx.AsyncClient:
        client = self._clients.get(url)
        if client is None or client.is_closed:
            client = self._clients[url] = httpx.AsyncClient(
                timeout=KEEPALIVE_INTERVAL,
                verify=shared_context(),
                limits=httpx.Limits(keepalive_expiry=KEPT_IDLE),
            )
        return client

    async def drop(self, url: str, client: httpx.AsyncClient) -> None:
        if self._clients.get(url) is client:
            del self._clients[url]
        with contextlib.suppress(Exception):
            await client.aclose()


KEPT_IDLE = 2.0
"""Seconds a kept keepalive connection may sit idle before the worker closes it."""
CLIENTS = KeptClients()


@contextlib.asynccontextmanager
async def keepalives(devices: Sequence[GrantedDevice]) -> AsyncIterator[dict[str, DeviceLink]]:
    """Keep every device of a job alive while the block runs; release them at its end."""
    links = {device.name: DeviceLink(device) for device in devices}
    for link in links.values():
        link._task = asyncio.create_task(link.run(), name=f"keepalive-{link.device.name}")
    try:
        yield links
    finally:
        for link in links.values():
            if link._task is not None:
                link._task.cancel()
        await asyncio.gather(*(link.release() for link in links.values()), return_exceptions=True)


@dataclass
class DeadlineToolset(WrapperToolset[Any]):
    """Fails a device call whose device went silent, instead of waiting for the job timeout."""

    link: DeviceLink | None = None

    async def call_tool(
        self, name: str, tool_args: dict[str, Any], ctx: RunContext[Any], tool: ToolsetTool[Any]
    ) -> Any:
        link = self.link
        if link is None:
            return await self.wrapped.call_tool(name, tool_args, ctx, tool)
        deadline, started, stopped_before = call_deadline(tool_args), time.monotonic(), link.stopped
        call = asyncio.create_task(self.wrapped.call_tool(name, tool_args, ctx, tool))
        try:
            while True:
                done, _ = await asyncio.wait({call}, timeout=CHECK_PERIOD)
                if done:
                    return call.result()
                failure = _why_abandon(link, name, deadline, started, stopped_before)
                if failure is not None:
                    log.warning("device %s: %s", link.device.name, failure)
                    raise ToolFailed(failure)
        finally:
            if not call.done():
                call.cancel()
                with contextlib.suppress(BaseException):
                    await call


def _why_abandon(
    link: DeviceLink, tool: str, deadline: float, started: float, stopped_before: int
) -> str | None:
    """Why a running call on ``link`` must be given up now, or None to keep waiting."""
    device = link.device.name
    if link.stopped > stopped_before:
        return (
            f"{device}: {tool} was stopped by its host's deadman: this worker's keepalives did not "
            f"reach it for {SILENCE_LIMIT:g} s; check the network to {link.device.url}, then try again"
        )
    loss = link.lost_and_back_since(started)
    if loss is not None:
        return (
            f"{device} was unreachable for {loss[1] - loss[0]:.1f} s during {tool}; its host stops a "
            "motion whose owner goes quiet (deadman), so the call was given up; try again"
        )
    if time.monotonic() - started > deadline and link.quiet_for() > SILENCE_LIMIT:
        return (
            f"{device} is unreachable: no answer from {link.device.url} for {link.quiet_for():.1f} s, "
            f"and {tool} was due within {deadline:.0f} s; its host stops the robot by itself (deadman). "
            "Check the network or the host, then try again"
        )
    return None
