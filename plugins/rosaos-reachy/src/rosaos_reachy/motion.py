"""Motion, one at a time: every movement goes through :class:`MotionController`.

The device is ``shared`` (any number of processes may hold it), so two processes may ask for
motion at once. Motions never run side by side: a new one interrupts the running one (the
daemon's ``stop_move`` for a goto, a cancel flag for a streamed emotion), waits for it to end,
then starts. The last request wins, as on the robot itself.

The controller also remembers the *commanded* posture. ``get_state`` reports it while the
measured posture is within a small deadband of it (a head sagging a millimetre under its own
weight, or MuJoCo's physics settling, is still "at" its target; the SDK's daemon reasons the
same way about its rest pose), and the measurement otherwise.

Motions are *foreground* (a tool a process called) or *background* (the companion's turns,
:mod:`rosaos_reachy.companion`): a background motion starts only when nothing moves, and
:attr:`MotionController.busy` tells the companion to keep still while a foreground one runs.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from dataclasses import dataclass

from reachy_mini.motion.move import Move

from rosaos_reachy.robot import HeadPose, Posture, RobotLink

log = logging.getLogger(__name__)

DEADBAND_DEG = 1.5
DEADBAND_MM = 3.0
DEADBAND_ANTENNA_DEG = 3.0
SETTLE_TIMEOUT_S = 2.5
"""After a goto, wait at most this long for the measured pose to reach the deadband."""


@dataclass(frozen=True)
class Reported:
    """What ``get_state`` shows: the commanded posture where it was reached, else the measured one."""

    posture: Posture
    measured: Posture
    settled: bool


def settled_view(commanded: Posture | None, measured: Posture) -> Reported:
    """Per part (head, antennas, body), the commanded value if the measurement is within the deadband."""
    if commanded is None:
        return Reported(measured, measured, False)
    head_ok = measured.head.close_to(commanded.head, DEADBAND_DEG, DEADBAND_MM)
    antennas_ok = all(
        abs(m - c) <= DEADBAND_ANTENNA_DEG for m, c in zip(measured.antennas, commanded.antennas, strict=True)
    )
    body_ok = abs(measured.body_yaw - commanded.body_yaw) <= DEADBAND_DEG
    posture = Posture(
        commanded.head if head_ok else measured.head,
        commanded.antennas if antennas_ok else measured.antennas,
        commanded.body_yaw if body_ok else measured.body_yaw,
    )
    return Reported(posture, measured, head_ok and antennas_ok and body_ok)


class MotionController:
    """Serializes motion on one robot; the latest request interrupts the running one."""

    def __init__(self, robot: RobotLink) -> None:
        self.robot = robot
        self.commanded: Posture | None = None
        self.current: str | None = None
        """Name of the running motion ("look", "emotion happy", ...), None when idle."""
        self._lock = asyncio.Lock()
        self._task: asyncio.Task[None] | None = None
        self._cancel = threading.Event()
        self._uses_daemon_move = False
        self._background = False
        self._foreground = 0
        self.foreground_ended = 0.0
        """``time.monotonic()`` when the last foreground motion ended (the companion waits a little)."""
        self.before_foreground: Callable[[], Awaitable[None]] | None = None
        """Called before a foreground motion starts: the companion zeroes its offsets."""

    @property
    def busy(self) -> bool:
        """A foreground motion is under way (moving, or waiting for the pose to settle)."""
        running = self._task is not None and not self._task.done() and not self._background
        return self._foreground > 0 or running

    @contextlib.asynccontextmanager
    async def _foreground_motion(self) -> AsyncIterator[None]:
        self._foreground += 1
        try:
            if self.before_foreground is not None:
                with contextlib.suppress(Exception):
                    await self.before_foreground()
            yield
        finally:
            self._foreground -= 1
            self.foreground_ended = time.monotonic()

    def view(self) -> Reported:
        """The posture to report now (see :func:`settled_view`)."""
        return settled_view(self.commanded, self.robot.measured())

    async def goto(self, target: Posture, duration: float, label: str, *, body: bool = True) -> Reported:
        """Interrupt, move to ``target`` and wait for it (and for the physics to settle)."""
        async with self._foreground_motion():
            task = await self._start(label, lambda: self._goto(target, duration, body), daemon_move=True)
            await self._wait(task)
            return await self.settle()

    async def goto_in_background(self, target: Posture, duration: float, label: str) -> bool:
        """Start a background move to ``target`` if nothing moves; False (nothing done) otherwise.

        It does not wait: any foreground motion interrupts it, as the newer request.
        """
        async with self._lock:
            if self.busy or (self._task is not None and not self._task.done()):
                return False
            self._begin(label, lambda: self._goto(target, duration, True), daemon_move=True, background=True)
            return True

    async def play(self, move: Move, end: Posture, label: str, *, wait: bool) -> float:
        """Interrupt and stream ``move`` (an emotion or dance), ending at ``end``.

        Returns its duration at once, or after it has played when ``wait``.
        """
        async with self._foreground_motion():
            task = await self._start(label, lambda: self._stream(move, end), daemon_move=False)
            if wait:
                await self._wait(task)
        return float(move.duration)

    async def run(self, label: str, action: Callable[[], None], result: Posture) -> Reported:
        """Interrupt and run a blocking SDK routine (wake up, go to sleep) that ends at ``result``."""

        def body() -> None:
            self.commanded = result
            action()

        async with self._foreground_motion():
            task = await self._start(label, body, daemon_move=True)
            await self._wait(task)
            return await self.settle()

    async def stop(self) -> bool:
        """Stop the running motion where it is. True if something was moving."""
        async with self._foreground_motion(), self._lock:
            moving = self._task is not None and not self._task.done()
            await self._interrupt()
            if moving:
                # Hold still where it stopped: that is now the commanded posture.
                self.commanded = self.robot.measured()
            return moving

    async def settle(self, timeout: float = SETTLE_TIMEOUT_S) -> Reported:
        """Wait until the measured posture is within the deadband of the commanded one (or timeout)."""
        deadline = time.monotonic() + timeout
        view = self.view()
        while not view.settled and time.monotonic() < deadline and self.current is None:
            await asyncio.sleep(0.05)
            view = self.view()
        return view

    async def close(self) -> None:
        """Stop motion before the connection goes away."""
        with contextlib.suppress(Exception):
            await self.stop()

    # --- internals ----------------------------------------------------------------------------

    async def _start(self, label: str, body: Callable[[], None], *, daemon_move: bool) -> asyncio.Task[None]:
        async with self._lock:
            await self._interrupt()
            return self._begin(label, body, daemon_move=daemon_move, background=False)

    def _begin(
        self, label: str, body: Callable[[], None], *, daemon_move: bool, background: bool
    ) -> asyncio.Task[None]:
        self._cancel = threading.Event()
        self._uses_daemon_move = daemon_move
        self._background = background
        self.current = label
        task = asyncio.create_task(self._run(label, body))
        self._task = task
        return task

    async def _run(self, label: str, body: Callable[[], None]) -> None:
        try:
            await asyncio.to_thread(body)
        except Exception:
            log.exception("reachy motion %r failed", label)
            raise
        finally:
            if self._task is asyncio.current_task():
                self.current = None
                if not self._background:  # a play() that returned at its start ends here
                    self.foreground_ended = time.monotonic()

    async def _interrupt(self) -> None:
        task = self._task
        if task is None or task.done():
            return
        self._cancel.set()
        if self._uses_daemon_move:
            await asyncio.to_thread(self.robot.stop_move)
        with contextlib.suppress(Exception):
            await asyncio.wait_for(asyncio.shield(task), timeout=5.0)
        self.current = None

    async def _wait(self, task: asyncio.Task[None]) -> None:
        # shield: a caller that gives up (the MCP request is cancelled) must not cancel the
        # thread's bookkeeping; the motion itself is stopped only by a newer motion or stop().
        await asyncio.shield(task)

    def _goto(self, target: Posture, duration: float, body: bool) -> None:
        if not body and self.commanded is not None:
            target = Posture(target.head, target.antennas, self.commanded.body_yaw)
        cancel = self._cancel  # this motion's flag: _begin gives the next motion a new one
        self.commanded = target
        self.robot.goto(target, duration, body=body, cancel=cancel)

    def _stream(self, move: Move, end: Posture) -> None:
        finished = self.robot.stream(move, self._cancel)
        self.commanded = end if finished else self.robot.measured()


def goto_duration(
    start: Posture | None, target: Posture, minimum: float = 0.5, maximum: float = 2.0
) -> float:
    """A calm duration for a move: longer for larger angles (about 90°/s), within bounds."""
    if start is None:
        return maximum
    distance = max(
        abs(target.head.yaw - start.head.yaw),
        abs(target.head.pitch - start.head.pitch),
        abs(target.head.roll - start.head.roll),
        abs(target.body_yaw - start.body_yaw),
        *(abs(a - b) for a, b in zip(target.antennas, start.antennas, strict=True)),
    )
    return max(minimum, min(maximum, 0.3 + distance / 90.0))


def head_toward(start: Posture, yaw: float, pitch: float, roll: float) -> Posture:
    """The posture looking at ``yaw`` (relative to the body), ``pitch`` and ``roll``, head centred."""
    return Posture(HeadPose(roll=roll, pitch=pitch, yaw=start.body_yaw + yaw), start.antennas, start.body_yaw)
