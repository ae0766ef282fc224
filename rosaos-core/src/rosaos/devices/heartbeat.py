"""The device host's heartbeat: a line its event loop writes on stdout every ``interval`` seconds.

Why not an HTTP probe: on a busy machine a request to a host that serves a hundred instances
waits behind their MCP sessions, so a probe with a timeout says "late" when the host is merely
busy. A timer on the host's event loop fires after one turn of the loop, however many requests
are queued; its line arrives a little late under load and not at all when the loop is stuck or
the process is stopped. The supervisor reads these lines (:class:`HostProcess.last_tick`) as the
one liveness signal of all the instances the host serves (:mod:`rosaos.devices.liveness`).

The write never blocks the loop: if nobody reads the pipe and it fills, beats are dropped.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
from typing import TextIO

TICK = b'{"tick": true}\n'


def is_tick(reply: dict[str, object]) -> bool:
    """Whether a line the host wrote is a heartbeat (not a handshake)."""
    return reply.get("tick") is True


async def beat(stream: TextIO, interval: float) -> None:
    """Write :data:`TICK` on ``stream`` every ``interval`` seconds until cancelled."""
    stream.flush()
    fd = stream.fileno()
    while True:
        await asyncio.sleep(interval)
        # The handshake is written with ordinary blocking writes; a beat is written whole or not at all.
        with contextlib.suppress(BlockingIOError, BrokenPipeError):
            os.set_blocking(fd, False)
            try:
                os.write(fd, TICK)
            finally:
                os.set_blocking(fd, True)
