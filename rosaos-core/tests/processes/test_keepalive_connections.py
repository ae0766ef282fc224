"""A worker's keepalives reuse one connection per host from job to job, and start afresh after a failure.

Building a client and a connection per job cost a light switch about a millisecond on 2 cores
(issue 26, part 8). When keepalives go is not changed: each job's first is sent at once, and its
release at the end. The host here is a real uvicorn server with the deadman's own ``/keepalive``
endpoint; it notes the client's address of every request, which names the connection.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from dataclasses import dataclass, field

import pytest_asyncio
import uvicorn
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import JSONResponse
from starlette.routing import Route

from rosaos.devices.deadman import KEEPALIVE_INTERVAL
from rosaos.devices.serve import bind_socket
from rosaos.processes.jobs import GrantedDevice
from rosaos.processes.keepalive import keepalives

from .processes_support import eventually


@dataclass
class Host:
    url: str = ""
    heard: list[tuple[str, bool]] = field(default_factory=list)
    """(client address, release?) of every keepalive, in order."""
    stall_next: bool = False


@pytest_asyncio.fixture
async def host() -> AsyncIterator[Host]:
    """A device host's keepalive endpoint on loopback."""
    seen = Host()

    async def keepalive(request: Request) -> JSONResponse:
        client = request.client
        seen.heard.append(
            (f"{client.host}:{client.port}" if client else "?", "release" in request.query_params)
        )
        if seen.stall_next:  # answered only after the worker gave up on it
            seen.stall_next = False
            await asyncio.sleep(KEEPALIVE_INTERVAL * 2)
        return JSONResponse({"armed": False, "stopped": 0})

    app = Starlette(routes=[Route("/keepalive", keepalive, methods=["POST"])])
    sock = bind_socket("127.0.0.1", 0)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning", lifespan="off"))
    task = asyncio.create_task(server.serve(sockets=[sock]))
    await eventually(lambda: server.started, what="the host to start")
    address, port = sock.getsockname()[:2]
    seen.url = f"http://{address}:{port}/mcp"
    yield seen
    server.should_exit = True
    await task
    sock.close()


def _device(url: str) -> GrantedDevice:
    return GrantedDevice(name="lamp", driver="test", url=url, token="t", description="", prompt="")


async def _job(host: Host) -> None:
    """What a short job does: its keepalives run while it does, and it ends at once."""
    before = len(host.heard)
    async with keepalives([_device(host.url)]):
        await eventually(lambda: len(host.heard) > before, what="the job's first keepalive")


async def test_the_next_job_keeps_alive_over_the_same_connection(host: Host) -> None:
    await _job(host)
    await eventually(lambda: len(host.heard) == 2, what="the first job's release")
    await _job(host)
    await eventually(lambda: len(host.heard) == 4, what="the second job's release")
    assert [release for _, release in host.heard] == [False, True, False, True]
    assert len({address for address, _ in host.heard}) == 1, host.heard


async def test_after_a_keepalive_fails_the_next_goes_on_a_fresh_connection(host: Host) -> None:
    await _job(host)  # a kept connection to this host
    host.stall_next = True
    async with keepalives([_device(host.url)]):
        # the stalled one times out; the next one is sent on a new connection
        await eventually(lambda: len(host.heard) >= 4, what="a keepalive after the stalled one")
    kept, stalled, after = host.heard[0][0], host.heard[2][0], host.heard[3][0]
    assert stalled == kept and after != kept, host.heard
