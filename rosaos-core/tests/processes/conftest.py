"""Real servers on loopback for the process tests: two test devices and a kernel stand-in.

The devices are small FastMCP servers (``set_level`` 0-100 and ``get_state``) served by the same
:func:`rosaos.devices.serve.serve_http` that hosts real drivers, behind a bearer token. The kernel
stand-in records every ``POST /event`` body, so tests see that workers post none.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator
from typing import Any

import pytest
import pytest_asyncio
import uvicorn
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import JSONResponse
from starlette.routing import Route

from rosaos.devices.serve import bind_socket, serve_http

from .processes_support import (
    KERNEL_TOKEN,
    TOKEN,
    KernelStandIn,
    LoopbackDevice,
    build_test_device,
    eventually,
)


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def devices() -> AsyncIterator[dict[str, LoopbackDevice]]:
    """Two test devices, ``lamp`` and ``fan``, each on its own loopback port."""
    async with contextlib.AsyncExitStack() as stack:
        served = {}
        for name in ("lamp", "fan"):
            state: dict[str, Any] = {"level": 0}
            device = await stack.enter_async_context(serve_http(build_test_device(name, state), TOKEN))
            served[name] = LoopbackDevice(name, device.url, state)
        yield served


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel() -> AsyncIterator[KernelStandIn]:
    """A kernel stand-in on loopback that requires the kernel token."""
    stand_in = KernelStandIn(url="")

    async def post_event(request: Request) -> JSONResponse:
        if request.headers.get("authorization") != f"Bearer {KERNEL_TOKEN}":
            return JSONResponse({"detail": "wrong bearer token"}, status_code=401)
        stand_in.bodies.append(await request.json())
        return JSONResponse({"id": len(stand_in.bodies)}, status_code=202)

    app = Starlette(routes=[Route("/event", post_event, methods=["POST"])])
    sock = bind_socket("127.0.0.1", 0)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", lifespan="off"))
    task = asyncio.create_task(server.serve(sockets=[sock]))
    await eventually(lambda: server.started, what="the kernel stand-in to start")
    host, port = sock.getsockname()[:2]
    stand_in.url = f"http://{host}:{port}"
    yield stand_in
    server.should_exit = True
    await task
    sock.close()


@pytest.fixture(scope="module")
def unreachable_url() -> str:
    """A loopback URL nobody listens on (the port was bound, then released)."""
    sock = bind_socket("127.0.0.1", 0)
    host, port = sock.getsockname()[:2]
    sock.close()
    return f"http://{host}:{port}/event"
