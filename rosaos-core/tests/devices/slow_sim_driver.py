"""The ``slowsim`` driver for the health-check tests: a simulator as slow as its ``sim`` table says.

Installed by the ``slowsim`` fixture (``test_health.py``) the way pip installs a driver (copied
into a site dir, with an entry point), so ``load_drivers()`` in the commands finds it. ``sim`` keys:

- ``start_seconds``: how long ``start`` takes; ``-1``: it never finishes;
- ``answer_seconds``: how long ``get_state`` takes; ``-1``: it never answers.

Like rosaos-ros, it cannot start two instances at once in one process: a start that overlaps
another fails. ``STARTED`` records every instance that was started in this process.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from fastmcp import FastMCP

from rosaos import hookimpl
from rosaos.drivers import DeviceBackend, DeviceContext, DeviceError, DriverSpec

STARTED: list[str] = []
_starting: set[str] = set()


async def _take(seconds: float) -> None:
    if seconds < 0:
        await asyncio.Event().wait()  # never
    await asyncio.sleep(seconds)


class SlowSim(DeviceBackend):
    simulated = True

    def __init__(self, ctx: DeviceContext) -> None:
        self.instance = ctx.instance
        self.start_seconds = float(ctx.sim.get("start_seconds", 0))
        self.answer_seconds = float(ctx.sim.get("answer_seconds", 0))

    async def start(self) -> None:
        if _starting:
            raise DeviceError(
                f"{self.instance}: {', '.join(sorted(_starting))} is starting in this process too; "
                "slowsim starts one instance at a time"
            )
        _starting.add(self.instance)
        STARTED.append(self.instance)
        try:
            await _take(self.start_seconds)
        finally:
            _starting.discard(self.instance)


def slow_server(ctx: DeviceContext, sim: SlowSim) -> FastMCP:
    server = FastMCP(ctx.instance)

    @server.tool(annotations={"readOnlyHint": True})
    async def get_state() -> dict[str, Any]:
        """How long this simulator took to start."""
        await _take(sim.answer_seconds)
        return {"started_in": sim.start_seconds}

    return server


SPEC = DriverSpec(
    name="slowsim",
    title="Slow simulator",
    description="A simulator that takes its time to start and to answer.",
    concurrency="shared",
    prompt="A test device.",
    server=slow_server,
    backends={"sim": SlowSim},
    demo={},
)


@hookimpl
def register_drivers(register: Callable[[DriverSpec], None]) -> None:
    register(SPEC)
