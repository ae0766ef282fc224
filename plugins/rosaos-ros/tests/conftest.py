"""Fixtures: a robot instance on the rosbridge simulator, driven through FastMCP's in-memory client.

The driver always reaches the simulator over a real WebSocket with roslibpy, as it would a robot;
only the MCP hop is in memory here (tests of the HTTP hop use ``serve_http`` themselves).
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import AsyncIterator, Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from fastmcp import Client

from rosaos.drivers import DeviceContext
from rosaos_ros.backend import RosBackend
from rosaos_ros.plugin import real_backend, sim_backend
from rosaos_ros.profiles import load_profile
from rosaos_ros.server import build_server
from rosaos_ros.settings import RosSettings
from rosaos_ros.sim import Simulator, SimulatorThread
from rosaos_ros.sim.world import DiffDriveWorld


def context(
    tmp_path: Path, instance: str = "turtlebot", backend: str = "sim", sim: Any = None, **settings: Any
) -> DeviceContext:
    """The context the hosting layer would build for an instance with these settings and sim table."""
    return DeviceContext(
        instance=instance,
        description="TurtleBot 4 in the test arena",
        settings=RosSettings.model_validate(settings),
        backend="sim" if backend == "sim" else "real",
        sim=sim if sim is not None else {},
        data_dir=tmp_path,
    )


@dataclass
class Robot:
    """A started backend and an MCP client on its server."""

    client: Client[Any]
    backend: RosBackend

    @property
    def world(self) -> DiffDriveWorld:
        """The simulated robot's physics (sim backend only)."""
        assert self.backend.simulator is not None
        return self.backend.simulator.simulator.world

    @property
    def simulator(self) -> SimulatorThread:
        assert self.backend.simulator is not None
        return self.backend.simulator

    async def call(self, tool: str, **args: Any) -> Any:
        """Call a tool and return its structured result."""
        result = await self.client.call_tool(tool, args)
        return result.structured_content

    async def error(self, tool: str, **args: Any) -> str:
        """Call a tool that must fail; return the error text the model would read."""
        result = await self.client.call_tool(tool, args, raise_on_error=False)
        assert result.is_error, f"{tool}({args}) should have failed: {result.structured_content}"
        return " ".join(getattr(block, "text", "") for block in result.content)


OpenRobot = Callable[..., contextlib.AbstractAsyncContextManager[Robot]]


@pytest.fixture
def open_robot(tmp_path: Path) -> OpenRobot:
    """``async with open_robot(sim={"docked": False}, profile="turtlebot4") as robot:`` on the simulator.

    Keyword arguments are instance settings; ``sim`` is the sim table. A context manager rather
    than an async fixture, so the MCP client is entered and left in the same task.
    """

    @contextlib.asynccontextmanager
    async def open_(sim: Any = None, instance: str = "turtlebot", **settings: Any) -> AsyncIterator[Robot]:
        settings.setdefault("profile", "turtlebot4")
        ctx = context(tmp_path, instance, sim={"docked": False} if sim is None else sim, **settings)
        backend = sim_backend(ctx)
        try:
            await backend.start()
            async with Client(build_server(ctx, backend)) as client:
                yield Robot(client, backend)
        finally:
            await backend.close()

    return open_


@pytest.fixture
def simulator() -> Iterator[Callable[..., SimulatorThread]]:
    """``simulator(profile="turtlebot4", **state)`` starts a rosbridge simulator in a thread on a free port."""
    started: list[SimulatorThread] = []

    def start(profile: str = "turtlebot4", token: str | None = None, **state: Any) -> SimulatorThread:
        thread = SimulatorThread(Simulator(load_profile(profile), state, token=token))
        thread.start()
        started.append(thread)
        return thread

    yield start
    for thread in started:
        thread.stop()


@pytest.fixture
def open_real(tmp_path: Path) -> Callable[..., contextlib.AbstractAsyncContextManager[Robot]]:
    """``async with open_real(port, **settings) as robot:``: the ``real`` backend pointed at a port."""

    @contextlib.asynccontextmanager
    async def open_(port: int, **settings: Any) -> AsyncIterator[Robot]:
        settings.setdefault("profile", "turtlebot4")
        ctx = context(tmp_path, backend="real", host="127.0.0.1", rosbridge_port=port, **settings)
        backend = real_backend(ctx)
        try:
            await backend.start()
            async with Client(build_server(ctx, backend)) as client:
                yield Robot(client, backend)
        finally:
            await backend.close()

    return open_


async def _eventually(check: Callable[[], bool], timeout: float = 5.0, what: str = "condition") -> float:
    """Poll ``check`` until it holds; return the seconds it took. Fails after ``timeout``."""
    started = time.monotonic()
    while not check():
        if time.monotonic() - started > timeout:
            pytest.fail(f"{what} did not happen within {timeout:g} s")
        await asyncio.sleep(0.01)
    return time.monotonic() - started


@pytest.fixture
def eventually() -> Callable[..., Any]:
    """``await eventually(lambda: robot.world.linear == 0, what="a stop")``: poll, never sleep-assert."""
    return _eventually
