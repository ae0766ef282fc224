"""The rosbridge simulator as one object: a simulated robot behind a rosbridge WebSocket server.

:class:`Simulator` runs on the caller's event loop (the ``rosaos-ros-sim`` command);
:class:`SimulatorThread` runs one on its own loop in a daemon thread, which is how the driver's
``sim`` backend and the tests use it: the driver still reaches it over a real socket.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
from collections.abc import Callable, Collection, Coroutine, Mapping
from typing import Any, TypeVar

from pydantic import ValidationError

from rosaos_ros.profiles import Profile
from rosaos_ros.sim.graph import RosGraph
from rosaos_ros.sim.robot import SimulatedRobot
from rosaos_ros.sim.server import RosbridgeServer
from rosaos_ros.sim.world import DiffDriveWorld, SimState

T = TypeVar("T")


class SimulatorError(Exception):
    """The simulator cannot start; the message says why and what to change."""


def sim_state(values: Mapping[str, Any]) -> SimState:
    """Validate a ``sim`` table; :class:`SimulatorError` names the bad key and the allowed ones."""
    try:
        return SimState.model_validate(dict(values))
    except ValidationError as error:
        allowed = ", ".join(SimState.model_fields)
        problems = "; ".join(
            f"{'.'.join(str(part) for part in problem['loc']) or 'sim'}: {problem['msg']}"
            for problem in error.errors()
        )
        raise SimulatorError(f"sim: {problems} (allowed keys: {allowed})") from None


class Simulator:
    """One simulated robot served over rosbridge at ``ws://host:port``."""

    def __init__(
        self,
        profile: Profile,
        state: SimState | Mapping[str, Any] | None = None,
        *,
        host: str = "127.0.0.1",
        port: int = 0,
        token: str | None = None,
        origins: Collection[str] = (),
    ) -> None:
        self.profile = profile
        self.host = host
        self.port = port
        self.graph = RosGraph()
        initial = state if isinstance(state, SimState) else sim_state(state or {})
        self.robot = SimulatedRobot(profile, initial, self.graph)
        self.server = RosbridgeServer(self.graph, token, origins)
        self._ticker: asyncio.Task[None] | None = None

    @property
    def world(self) -> DiffDriveWorld:
        """The simulated physics (pose, velocities, dock, battery)."""
        return self.robot.world

    @property
    def url(self) -> str:
        return f"ws://{self.host}:{self.port}"

    async def start(self) -> None:
        """Start the physics and listen; ``port`` 0 becomes the port chosen."""
        await self.go_online()
        self._ticker = asyncio.get_running_loop().create_task(self.robot.run())

    async def stop(self) -> None:
        """Stop listening (dropping every client) and stop the physics."""
        await self.go_offline()
        if self._ticker is not None:
            self._ticker.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._ticker

    async def go_offline(self) -> None:
        """Drop every client and stop listening, as a robot that lost its network; physics go on."""
        await self.server.stop()

    async def go_online(self) -> None:
        """Listen again, on the same port once one was chosen."""
        try:
            self.port = await self.server.start(self.host, self.port)
        except OSError as error:
            raise SimulatorError(
                f"cannot listen on {self.host}:{self.port}: {error.strerror}; pick another --port"
            ) from None

    async def serve_forever(self) -> None:
        """Start, then run until cancelled."""
        await self.start()
        try:
            await asyncio.Event().wait()
        finally:
            await self.stop()


class SimulatorThread:
    """A :class:`Simulator` on its own event loop in a daemon thread."""

    def __init__(self, simulator: Simulator) -> None:
        self.simulator = simulator
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._thread: threading.Thread | None = None
        self._error: BaseException | None = None

    def start(self, timeout: float = 10.0) -> None:
        """Start the thread and return once the simulator listens; raise what stopped it otherwise."""
        ready = threading.Event()

        async def main() -> None:
            self._loop = asyncio.get_running_loop()
            self._stop = asyncio.Event()
            await self.simulator.start()
            ready.set()
            try:
                await self._stop.wait()
            finally:
                await self.simulator.stop()

        def run() -> None:
            try:
                asyncio.run(main())
            except BaseException as error:  # handed to the starting thread
                self._error = error
            finally:
                ready.set()

        self._thread = threading.Thread(target=run, name="rosaos-ros-sim", daemon=True)
        self._thread.start()
        if not ready.wait(timeout):
            raise SimulatorError(f"the simulator did not start within {timeout:g} s")
        if self._error is not None:
            raise self._error

    def call(self, work: Callable[[], Coroutine[Any, Any, T]], timeout: float = 10.0) -> T:
        """Run a coroutine on the simulator's loop and wait for its result."""
        if self._loop is None:
            raise SimulatorError("the simulator thread is not running")
        return asyncio.run_coroutine_threadsafe(work(), self._loop).result(timeout)

    def stop(self, timeout: float = 10.0) -> None:
        """Stop the simulator and join its thread."""
        if self._loop is not None and self._stop is not None and not self._loop.is_closed():
            with contextlib.suppress(RuntimeError):  # the loop already ended
                self._loop.call_soon_threadsafe(self._stop.set)
        if self._thread is not None:
            self._thread.join(timeout)
