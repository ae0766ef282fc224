"""The device host's deadman: a motion runs only while its owner is heard from.

A worker names itself on every request to a device with the :data:`OWNER_HEADER` header. The
first tool call that is not read-only *arms* the deadman for that owner; from then on the owner
must be heard at least every :data:`SILENCE_LIMIT` seconds (any request with its header counts;
the worker sends ``POST /keepalive`` every :data:`KEEPALIVE_INTERVAL` s while its job runs). If
the owner goes quiet — a dead worker, a dead kernel, or a network that drops packets without
closing anything — the host calls the driver's ``safe_stop`` itself and disarms. A worker whose
job ended releases its arming (``POST /keepalive?release=1``), so an idle warm worker is no owner.

Why at the host: only the host is sure to be on the robot's side of a partition. The kernel's
emergency stop and the worker's own ``safe_stop`` both need the network this guards against.

Calls without the owner header (a person's ``rosaos devices call``, the conformance kit) are not
armed: nobody promised to keep them alive. Drivers whose ``safe_stop`` does nothing get no deadman.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from fastmcp.server.dependencies import get_http_headers
from fastmcp.server.middleware import CallNext, Middleware, MiddlewareContext
from starlette.requests import Request
from starlette.responses import JSONResponse

log = logging.getLogger("rosaos.devices.deadman")

OWNER_HEADER = "x-rosaos-owner"
"""Who a request to a device host speaks for: a worker sends ``worker-<pid>-<random>``."""
KEEPALIVE_PATH = "/keepalive"
KEEPALIVE_INTERVAL = 0.4
"""Seconds between a worker's keepalives (the promise is at least every 0.5 s)."""
SILENCE_LIMIT = 1.5
"""Seconds of silence from an armed owner after which the host stops the device."""
CHECK_PERIOD = 0.1
NOT_ARMING = frozenset({"safe_stop", "stop", "stop_motion"})
"""Tools that stop rather than actuate: calling one arms nothing."""


@dataclass
class DeadmanFiring:
    """One time the deadman stopped the device, for the log, ``/keepalive`` and tests."""

    owner: str
    silent_for: float
    ok: bool
    detail: str
    at: float = field(default_factory=time.time)


class Deadman:
    """Tracks the armed owners of one device and stops it when one of them goes quiet."""

    def __init__(
        self,
        instance: str,
        stop: Callable[[], Awaitable[None]],
        limit: float = SILENCE_LIMIT,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.instance = instance
        self.limit = limit
        self._stop = stop
        self._clock = clock
        self._armed: dict[str, float] = {}
        """Owner → when it was last heard."""
        self.firings: list[DeadmanFiring] = []
        self._wake = asyncio.Event()
        """Set when an owner is armed: :meth:`run` sleeps on it while nothing is armed."""

    @property
    def armed(self) -> list[str]:
        """The owners the device is waiting to hear from."""
        return sorted(self._armed)

    def heard(self, owner: str) -> None:
        """The owner sent something: its motion may go on."""
        if owner in self._armed:
            self._armed[owner] = self._clock()

    def arm(self, owner: str) -> None:
        """The owner started something that actuates: from now on it must keep talking."""
        self._armed[owner] = self._clock()
        self._wake.set()

    def release(self, owner: str) -> None:
        """The owner's job ended: it no longer owes keepalives."""
        self._armed.pop(owner, None)

    def fired_for(self, owner: str) -> int:
        """How many times the deadman stopped the device because ``owner`` went quiet."""
        return sum(1 for firing in self.firings if firing.owner == owner)

    async def check(self) -> None:
        """Stop the device once for every armed owner quiet for longer than the limit."""
        now = self._clock()
        quiet = [(owner, now - last) for owner, last in self._armed.items() if now - last > self.limit]
        for owner, silent_for in quiet:
            self._armed.pop(owner, None)
            log.warning(
                "%s: deadman: %s silent for %.1f s while armed; calling safe_stop",
                self.instance,
                owner,
                silent_for,
            )
            try:
                await self._stop()
            except Exception as error:  # the robot's own command timeout is the last resort
                log.exception("%s: deadman: safe_stop failed", self.instance)
                self.firings.append(DeadmanFiring(owner, silent_for, False, f"safe_stop failed: {error}"))
                continue
            self.firings.append(DeadmanFiring(owner, silent_for, True, "safe_stop done"))

    async def run(self) -> None:
        """Check every :data:`CHECK_PERIOD` s while an owner is armed, until cancelled.

        With nothing armed there is nothing to check: the loop waits for :meth:`arm` instead of
        waking ten times a second, which for three hundred lamps in one host was most of its
        idle CPU. An owner is armed before its call reaches the device, so no motion goes
        unwatched."""
        while True:
            if not self._armed:
                self._wake.clear()
                await self._wake.wait()
            await asyncio.sleep(CHECK_PERIOD)
            await self.check()


class ReadOnlyTools:
    """Which of a server's tools are read-only, by their ``readOnlyHint`` (unknown: not read-only)."""

    def __init__(self, server: FastMCP) -> None:
        self._server = server
        self._known: dict[str, bool] = {}

    async def __call__(self, name: str) -> bool:
        if name not in self._known:
            tool = await self._server.get_tool(name)
            hint = tool.annotations.read_only_hint if tool is not None and tool.annotations else None
            self._known[name] = bool(hint)
        return self._known[name]


class DeadmanMiddleware(Middleware):
    """Arms the deadman for the owner of every tool call that is not read-only."""

    def __init__(self, deadman: Deadman, read_only: ReadOnlyTools) -> None:
        self.deadman = deadman
        self.read_only = read_only

    async def on_call_tool(self, context: MiddlewareContext[Any], call_next: CallNext[Any, Any]) -> Any:
        owner = get_http_headers().get(OWNER_HEADER)
        name = getattr(context.message, "name", "")
        if not owner or name in NOT_ARMING or await self.read_only(name):
            return await call_next(context)
        self.deadman.arm(owner)
        fired = self.deadman.fired_for(owner)
        result = await call_next(context)
        if self.deadman.fired_for(owner) > fired:  # the call "ended" because the deadman stopped it
            raise ToolError(
                f"{self.deadman.instance}: {name} was stopped by the device host's deadman: it heard "
                f"nothing from its owner for {self.deadman.limit:g} s (a silent network, or a dead "
                "worker); the device is in its safe state; check the link, then try again"
            )
        return result


def keepalive_endpoint(deadman: Deadman) -> Callable[[Request], Awaitable[JSONResponse]]:
    """``POST /keepalive`` (behind the token): the owner is heard; ``?release=1`` ends its arming.

    The answer says whether the deadman stopped the device for this owner (``stopped``, a count),
    so a worker learns its motion was ended even when the tool call's own answer is lost."""

    async def keepalive(request: Request) -> JSONResponse:
        owner = request.headers.get(OWNER_HEADER, "")
        if not owner:
            return JSONResponse(
                {"error": f"send the {OWNER_HEADER} header naming who keeps the device alive"},
                status_code=400,
            )
        if request.query_params.get("release") in ("1", "true"):
            deadman.release(owner)
        else:
            deadman.heard(owner)
        return JSONResponse({"armed": owner in deadman.armed, "stopped": deadman.fired_for(owner)})

    return keepalive


class HeardMiddleware:
    """ASGI: any request that names an owner counts as hearing from it (a tool call is a keepalive)."""

    def __init__(self, app: Any, deadman: Deadman) -> None:
        self.app = app
        self.deadman = deadman

    async def __call__(self, scope: Any, receive: Any, send: Any) -> None:
        if scope["type"] == "http":
            for key, value in scope.get("headers", ()):
                if key == OWNER_HEADER.encode():
                    self.deadman.heard(value.decode("latin-1"))
                    break
        await self.app(scope, receive, send)


@contextlib.asynccontextmanager
async def running_deadman(
    server: FastMCP, instance: str, stop: Callable[[], Awaitable[None]], limit: float = SILENCE_LIMIT
) -> AsyncIterator[Deadman]:
    """Give ``server`` a deadman (middleware and ``/keepalive``) and run its checks until exit."""
    deadman = Deadman(instance, stop, limit)
    server.add_middleware(DeadmanMiddleware(deadman, ReadOnlyTools(server)))
    server.custom_route(KEEPALIVE_PATH, methods=["POST"])(keepalive_endpoint(deadman))
    _DEADMEN[id(server)] = deadman
    task = asyncio.create_task(deadman.run(), name=f"deadman-{instance}")
    try:
        yield deadman
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
        _DEADMEN.pop(id(server), None)


_DEADMEN: dict[int, Deadman] = {}


def deadman_of(server: FastMCP) -> Deadman | None:
    """The deadman :func:`running_deadman` gave ``server``, for the HTTP app to feed."""
    return _DEADMEN.get(id(server))
