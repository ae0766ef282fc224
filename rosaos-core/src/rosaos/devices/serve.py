"""Serve one device instance: build its backend and FastMCP server, and expose it over HTTP.

The lifecycle is the same everywhere a device runs (``rosaos serve-device``, the supervisor's
host processes, the conformance kit): :func:`open_device` starts the backend and builds the
server; :func:`serve_http` puts that server on streamable HTTP at ``/mcp`` behind the bearer
token, on a socket bound before serving so port 0 works and the URL is known up front.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
import weakref
from collections.abc import AsyncIterator, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import uvicorn
from fastmcp import FastMCP
from starlette.types import ASGIApp

from rosaos.auth import BearerAuthMiddleware, HostOriginGuard, bound_hosts
from rosaos.devices.deadman import HeardMiddleware, deadman_of, running_deadman
from rosaos.devices.host_notices import HOST_BOARDS, with_host_notices
from rosaos.devices.latch import add_latch
from rosaos.devices.world import DeviceInstance
from rosaos.drivers import SETS, DeviceBackend, DeviceError, no_safe_stop
from rosaos.fastmcp_spans import spans_off
from rosaos.notices.notice_board import NoticeBoard, notice_endpoint

MCP_PATH = "/mcp"
HEALTH_PATH = "/health"
NOTICES_PATH = "/notices"


@dataclass
class OpenDevice:
    """A started backend and the FastMCP server built on it."""

    instance: DeviceInstance
    backend: DeviceBackend
    server: FastMCP


@contextlib.asynccontextmanager
async def open_device(instance: DeviceInstance, data_dir: Path) -> AsyncIterator[OpenDevice]:
    """Start the instance's backend, build its server, and close the backend on exit.

    Raises :class:`DeviceError` if the driver is a placeholder, the backend fails to start,
    or the instance is remote (it is served elsewhere).
    """
    spans_off()  # every device server of this process: its spans go nowhere (rosaos/fastmcp_spans.py)
    spec = instance.spec
    if instance.is_remote:
        raise DeviceError(f"{instance.name} is remote ({instance.url}); it is served on its own host")
    if not spec.implemented:
        raise DeviceError(f"driver {spec.name!r} is not implemented yet; it cannot be served")
    ctx = instance.context(data_dir)
    backend = spec.backends[instance.backend](ctx)
    try:
        await backend.start()
        server = spec.server(ctx, backend)
        # Tool arguments are typed at the boundary: `true` is not a brightness, "50" is not 50.
        server.strict_input_validation = True
        _add_safe_stop(server, instance, backend)
        add_notice_route(server, ctx.notices)
        add_latch(server, instance.name, data_dir)  # the emergency stop holds here too (devices/latch.py)
        async with contextlib.AsyncExitStack() as stack:
            if spec.safe_stop is not no_safe_stop:  # a device with nothing to stop needs no deadman

                async def stop() -> None:
                    await spec.safe_stop(backend)

                await stack.enter_async_context(running_deadman(server, instance.name, stop))
            yield OpenDevice(instance, backend, server)
    finally:
        await backend.close()


def _add_safe_stop(server: FastMCP, instance: DeviceInstance, backend: DeviceBackend) -> None:
    """Every device server gets ``safe_stop``: the driver's emergency-stop action, callable remotely."""
    spec = instance.spec

    async def safe_stop() -> str:
        """Emergency stop: put this device in its safe state."""
        await spec.safe_stop(backend)
        return f"{instance.name}: safe stop done"

    server.tool(
        safe_stop,
        name="safe_stop",
        annotations=SETS,
    )


_BOARDS: weakref.WeakKeyDictionary[FastMCP, NoticeBoard] = weakref.WeakKeyDictionary()


def add_notice_route(server: FastMCP, board: NoticeBoard) -> None:
    """Every device server gets ``GET /notices`` (behind its token): the kernel long-polls it for the
    notices the driver posts with ``ctx.notify`` (:mod:`rosaos.notices.notice_board`)."""
    server.custom_route(NOTICES_PATH, methods=["GET"])(notice_endpoint(board))
    _BOARDS[server] = board  # so serve_http can end its long polls before stopping


def device_http_app(server: FastMCP, token: str, allowed_hosts: Iterable[str] = ()) -> ASGIApp:
    """The ASGI app for a device: MCP at ``/mcp``; ``/health`` open; everything else needs the token.

    ``POST /host/notices`` reads every board this process serves at once
    (:mod:`rosaos.devices.host_notices`).

    Only loopback and ``allowed_hosts`` may appear in ``Host``, and a browser only from the same
    origin (:class:`~rosaos.auth.HostOriginGuard`)."""
    mcp_app: ASGIApp = server.http_app(path=MCP_PATH)
    deadman = deadman_of(server)
    if deadman is not None:  # behind the token: only an authenticated request counts as heard
        mcp_app = HeardMiddleware(mcp_app, deadman)
    guarded = BearerAuthMiddleware(
        _with_health(with_host_notices(mcp_app, token)), token=token, open_paths=[HEALTH_PATH]
    )
    return HostOriginGuard(guarded, allowed_hosts=allowed_hosts)


def _with_health(app: Any) -> ASGIApp:
    async def wrapped(scope: Any, receive: Any, send: Any) -> None:
        if scope["type"] == "http" and scope.get("path") == HEALTH_PATH:
            body = b'{"status":"ok"}'
            await send(
                {
                    "type": "http.response.start",
                    "status": 200,
                    "headers": [(b"content-type", b"application/json")],
                }
            )
            await send({"type": "http.response.body", "body": body})
            return
        await app(scope, receive, send)

    return wrapped


def bind_socket(host: str, port: int) -> socket.socket:
    """Bind (without listening) so the port is ours before the server starts; 0 picks a free one."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    # IPPROTO_TCP explicitly: asyncio turns Nagle off (TCP_NODELAY) only for sockets created with
    # it, and with Nagle on every response waits ~40 ms for the client's delayed ACK.
    sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError as error:
        sock.close()
        raise DeviceError(f"cannot bind {host}:{port}: {error.strerror}; pick another --port") from None
    return sock


def url_for(sock: socket.socket) -> str:
    host, port = sock.getsockname()[:2]
    shown = f"[{host}]" if ":" in host else host
    return f"http://{shown}:{port}{MCP_PATH}"


class _QuietServer(uvicorn.Server):
    """A uvicorn server that wakes once a second while idle, not ten times.

    uvicorn's main loop sleeps 0.1 s between checks of ``should_exit``; the shared host runs one
    server per instance, so three hundred lamps woke its event loop 3000 times a second doing
    nothing, most of rosaOS's idle CPU. The once-a-second work (the ``Date`` header) is the same;
    :meth:`exit_now` makes a stop as prompt as before."""

    def __init__(self, config: uvicorn.Config) -> None:
        super().__init__(config)
        self._wake = asyncio.Event()

    def exit_now(self) -> None:
        self.should_exit = True
        self._wake.set()

    async def main_loop(self) -> None:
        ticks = 0
        while not await self.on_tick(ticks):
            ticks = (ticks + 10) % 864000  # a multiple of 10: on_tick's once-a-second branch runs
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._wake.wait(), IDLE_TICK)


IDLE_TICK = 1.0
"""Seconds between an idle device server's checks (uvicorn's own: 0.1)."""


@dataclass
class ServedDevice:
    """A device being served over HTTP in this process."""

    url: str
    server: _QuietServer
    task: asyncio.Task[None]
    notices: NoticeBoard | None = None

    async def stop(self) -> None:
        if self.notices is not None:
            self.notices.release_waiters()
        self.server.exit_now()
        with contextlib.suppress(asyncio.CancelledError):
            await self.task


@contextlib.asynccontextmanager
async def serve_http(
    server: FastMCP, token: str, host: str = "127.0.0.1", port: int = 0, allowed_hosts: Iterable[str] = ()
) -> AsyncIterator[ServedDevice]:
    """Serve ``server`` over streamable HTTP until the block exits. Yields once it accepts connections.

    ``allowed_hosts``: ``Host`` names besides loopback and ``host`` itself (``--allow-host``)."""
    sock = bind_socket(host, port)
    app = device_http_app(server, token, [*allowed_hosts, *bound_hosts(host)])
    config = uvicorn.Config(app, log_level="warning", lifespan="on", timeout_graceful_shutdown=2)
    uv_server = _QuietServer(config)
    task = asyncio.create_task(uv_server.serve(sockets=[sock]))
    served = ServedDevice(url_for(sock), uv_server, task, _BOARDS.get(server))
    if served.notices is not None:
        HOST_BOARDS.add(served.notices, token)
    try:
        while not uv_server.started:
            if task.done():
                task.result()  # re-raise the start-up failure
                raise DeviceError(f"device server on {host}:{port} stopped during start-up")
            await asyncio.sleep(0.01)
        yield served
    finally:
        if served.notices is not None:
            HOST_BOARDS.remove(served.notices)
        await served.stop()
        sock.close()
