"""Motion on the velocity topic: timed drives with a deadman, and closed-loop moves on odometry.

At most one motion runs at a time; a new one replaces the old. Each runs as a task of its own,
not of the tool call that started it, so a client that disconnects cannot leave it half-done:

- ``drive`` streams a twist at 20 Hz until its deadline, then sends a zero twist. Another
  ``drive`` before the deadline *renews* it (new velocities, new deadline, no stop in between):
  a drive that is not renewed ends in a zero twist at its deadline. The deadman watchdog thread
  (:mod:`rosaos_ros.deadman`) stops the robot if this loop ever misses that moment, or pauses
  for more than :data:`HEARTBEAT` s, by 0.1 s.
- ``move_distance`` and ``rotate`` run a proportional controller on odometry, slowing down near
  the target; they keep the watchdog armed 0.3 s ahead while they run.

The velocity stream is itself a deadman, as ``twist_mux`` treats its inputs: every loop arms the
watchdog at most :data:`HEARTBEAT` s ahead, a long ``drive`` or raw stream included, so a loop
that stalls (a blocked event loop, a starved process) is followed by a zero twist within 0.4 s,
not only at the end of the drive. As with ``twist_mux``, the stream goes on if its loop does.

Every motion ends with a zero twist, whatever ends it: done, stopped, superseded, error.
A cancelled tool call stops its motion (a robot never moves longer than it was asked to).
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Any

from rosaos.drivers import DeviceError
from rosaos_ros.deadman import DeadmanWatchdog
from rosaos_ros.messages import wrap_angle
from rosaos_ros.state import Odometry, RobotStateCache

log = logging.getLogger("rosaos_ros.motion")

RATE_HZ = 20
HEARTBEAT = 0.3
"""Seconds a motion loop arms the watchdog ahead: the longest the stream may pause before a zero twist."""
"""Closed-loop motions: the watchdog stops the robot if the controller skips this long."""
ODOMETRY_MAX_AGE = 0.5
DISTANCE_TOLERANCE = 0.005  # m
ANGLE_TOLERANCE = math.radians(0.5)
LINEAR_GAIN, MIN_LINEAR = 3.0, 0.03  # 1/s, m/s
ANGULAR_GAIN, MIN_ANGULAR = 4.0, 0.15  # 1/s, rad/s
HEADING_GAIN = 2.0  # keeps move_distance straight


@dataclass
class MotionResult:
    """How a motion ended, for the model."""

    motion: str
    outcome: str
    """``done``, ``started`` (drive without waiting), ``renewed``, ``stopped`` or ``timed out``."""
    detail: str
    seconds: float

    def as_dict(self) -> dict[str, Any]:
        return {
            "motion": self.motion,
            "outcome": self.outcome,
            "detail": self.detail,
            "seconds": round(self.seconds, 2),
        }


@dataclass
class _DriveCommand:
    linear: float
    angular: float
    deadline: float
    started: float
    result: asyncio.Future[MotionResult]

    def end(self, outcome: str, detail: str) -> None:
        if not self.result.done():
            self.result.set_result(MotionResult("drive", outcome, detail, time.monotonic() - self.started))

    def fail(self, error: DeviceError) -> None:
        if not self.result.done():
            self.result.set_exception(error)


@dataclass
class _Run:
    kind: str
    task: asyncio.Task[None]
    result: asyncio.Future[MotionResult]
    started: float


class MotionController:
    """Owns the velocity topic of one robot."""

    def __init__(
        self,
        instance: str,
        send_twist: Callable[[float, float], None],
        state: RobotStateCache,
        deadman: DeadmanWatchdog,
        max_turn_while_driving: float,
    ) -> None:
        self.instance = instance
        self.state = state
        self.deadman = deadman
        self.period = 1 / RATE_HZ
        self._send_twist = send_twist
        self._max_heading_rate = max_turn_while_driving
        self._run: _Run | None = None
        self._drive: _DriveCommand | None = None
        self._stop_reason = ""
        self._abort_error: DeviceError | None = None

    @property
    def busy(self) -> str | None:
        """The running motion's kind, or None."""
        return self._run.kind if self._run is not None and not self._run.task.done() else None

    # Motions

    async def drive(self, linear: float, angular: float, duration: float, wait: bool) -> MotionResult:
        """Drive at ``linear`` m/s and ``angular`` rad/s for ``duration`` s, renewing a running drive."""
        loop = asyncio.get_running_loop()
        now = time.monotonic()
        command = _DriveCommand(linear, angular, now + duration, now, loop.create_future())
        if self.busy == "drive" and self._drive is not None:
            self._drive.end("renewed", "replaced by a newer drive command before its deadline")
            self._drive = command
            # The watchdog is armed for the old command's deadline until the loop's next tick; a
            # tick that comes late on a busy machine would stop the renewed drive (CI, 2026-11-26).
            self.deadman.arm(min(command.deadline, now + HEARTBEAT))
        else:
            await self.stop("replaced by a drive command")
            self._drive = command
            self._start("drive", self._drive_loop)
        if not wait:
            return MotionResult(
                "drive",
                "started",
                f"driving at {linear:g} m/s, {angular:g} rad/s; it stops by itself in {duration:g} s "
                "unless drive is called again before then",
                0.0,
            )
        return await self._wait(command.result)

    async def move_distance(self, meters: float, speed: float) -> MotionResult:
        """Drive ``meters`` straight (negative: backward) at up to ``speed`` m/s, closed loop on odometry."""
        await self.stop("replaced by move_distance")
        if self.state.profile.odom is None:
            return await self._timed("move_distance", math.copysign(speed, meters), 0.0, abs(meters) / speed)
        await self.state.wait_for_messages(sources={"odom"})  # the first odometry, right after start
        run = self._start("move_distance", lambda: self._move_loop(meters, speed))
        return await self._wait(run.result)

    async def rotate(self, radians: float, speed: float) -> MotionResult:
        """Turn in place by ``radians`` (positive: left, counter-clockwise), closed loop on odometry."""
        await self.stop("replaced by rotate")
        if self.state.profile.odom is None:
            return await self._timed("rotate", 0.0, math.copysign(speed, radians), abs(radians) / speed)
        await self.state.wait_for_messages(sources={"odom"})
        run = self._start("rotate", lambda: self._rotate_loop(radians, speed))
        return await self._wait(run.result)

    async def stop(self, reason: str = "stopped") -> None:
        """End the running motion (if any) with a zero twist."""
        run, self._run = self._run, None
        if run is not None and not run.task.done():
            self._stop_reason = reason
            if self._drive is not None:
                self._drive.end("stopped", reason)
            run.task.cancel()
            await asyncio.gather(run.task, return_exceptions=True)
        self._zero()

    def abort(self, error: DeviceError) -> None:
        """End the running motion with ``error`` without waiting (the connection dropped: nothing can be sent).

        The robot's own command timeout stops it; the waiting tool call reports ``error``.
        """
        if self._run is not None and not self._run.task.done():
            self._abort_error = error
            if self._drive is not None:
                self._drive.fail(error)
            self._run.task.cancel()

    # Loops

    def _start(self, kind: str, body: Callable[[], Awaitable[MotionResult]]) -> _Run:
        loop = asyncio.get_running_loop()
        result: asyncio.Future[MotionResult] = loop.create_future()
        started = time.monotonic()
        self._stop_reason, self._abort_error = "", None

        async def run() -> None:
            try:
                outcome = await body()
                if not result.done():
                    result.set_result(outcome)
            except asyncio.CancelledError:
                if result.done():
                    pass
                elif self._abort_error is not None:
                    result.set_exception(self._abort_error)
                else:
                    reason = self._stop_reason or "stopped"
                    result.set_result(MotionResult(kind, "stopped", reason, time.monotonic() - started))
            except DeviceError as error:
                if not result.done():
                    result.set_exception(error)
            finally:
                self._zero()

        self._run = _Run(kind, loop.create_task(run()), result, started)
        return self._run

    async def _wait(self, result: asyncio.Future[MotionResult]) -> MotionResult:
        try:
            return await asyncio.shield(result)
        except asyncio.CancelledError:
            await self.stop("the tool call was cancelled")
            raise

    async def _drive_loop(self) -> MotionResult:
        while True:
            command = self._drive
            assert command is not None
            now = time.monotonic()
            if now >= command.deadline:
                detail = f"drove at {command.linear:g} m/s, {command.angular:g} rad/s, then stopped"
                command.end("done", detail)
                return MotionResult("drive", "done", detail, now - command.started)
            self.deadman.arm(min(command.deadline, now + HEARTBEAT))
            self._send_twist(command.linear, command.angular)
            await asyncio.sleep(min(self.period, command.deadline - now))

    async def stream(self, kind: str, send: Callable[[], None], duration: float, rate: float) -> MotionResult:
        """Call ``send`` (which publishes a velocity command) ``rate`` times a second for ``duration`` s.

        For raw messages on the velocity topic (``publish``, ``publish_for``): they get the same
        deadman as ``drive``, and a zero twist at the end.
        """
        await self.stop(f"replaced by {kind}")

        async def body() -> MotionResult:
            deadline, sent = time.monotonic() + duration, 0
            while (now := time.monotonic()) < deadline:
                self.deadman.arm(min(deadline, now + HEARTBEAT))
                send()
                sent += 1
                await asyncio.sleep(min(1 / rate, deadline - now))
            return MotionResult(
                kind,
                "done",
                f"sent {sent} velocity messages over {duration:g} s, then a zero twist",
                duration,
            )

        return await self._wait(self._start(kind, body).result)

    async def _timed(self, kind: str, linear: float, angular: float, duration: float) -> MotionResult:
        """Open loop, for a profile without odometry: a fixed twist for a computed time."""
        result = await self.stream(kind, lambda: self._send_twist(linear, angular), duration, RATE_HZ)
        result.detail = f"ran open loop for {duration:.1f} s (the profile has no odometry)"
        return result

    async def _odometry(self) -> Odometry:
        """Odometry no older than :data:`ODOMETRY_MAX_AGE`, for a closed loop.

        A stale reading is not yet a dead base driver: on a busy machine the odometry stream can
        pause for longer than the loop's bound. The robot then stands still (a zero twist) and
        waits up to :data:`~rosaos_ros.state.FIRST_MESSAGE_WAIT` for a fresh reading; only after
        that is the motion refused, so a blind robot never drives on its last reading.
        """
        try:
            return self.state.latest_odometry(ODOMETRY_MAX_AGE)
        except DeviceError:
            if self.state.odometry is None or self.state.profile.odom is None:
                raise
        self._zero()
        await self.state.wait_for_messages(since=time.monotonic() - ODOMETRY_MAX_AGE, sources={"odom"})
        return self.state.latest_odometry(ODOMETRY_MAX_AGE)

    async def _move_loop(self, meters: float, speed: float) -> MotionResult:
        start = await self._odometry()
        heading, began = start.yaw, time.monotonic()
        timeout = abs(meters) / speed * 2 + 1.5

        def travelled(odom: Odometry) -> float:
            return (odom.x - start.x) * math.cos(heading) + (odom.y - start.y) * math.sin(heading)

        while abs(remaining := meters - travelled(odom := await self._odometry())) > DISTANCE_TOLERANCE:
            if time.monotonic() - began > timeout:
                return MotionResult(
                    "move_distance",
                    "timed out",
                    f"moved {travelled(odom):.3f} m of {meters:g} m in {timeout:.0f} s; something may block the robot",
                    time.monotonic() - began,
                )
            linear = math.copysign(min(speed, max(MIN_LINEAR, LINEAR_GAIN * abs(remaining))), remaining)
            drift = wrap_angle(heading - odom.yaw)
            angular = max(-self._max_heading_rate, min(self._max_heading_rate, HEADING_GAIN * drift))
            self.deadman.arm(time.monotonic() + HEARTBEAT)
            self._send_twist(linear, angular)
            await asyncio.sleep(self.period)
        self._zero()
        detail = f"moved {travelled(await self._odometry()):.3f} m {'forward' if meters >= 0 else 'backward'} (asked {meters:g} m)"
        return MotionResult("move_distance", "done", detail, time.monotonic() - began)

    async def _rotate_loop(self, radians: float, speed: float) -> MotionResult:
        began = time.monotonic()
        last_yaw = (await self._odometry()).yaw
        turned = 0.0
        timeout = abs(radians) / speed * 2 + 1.5
        while True:
            yaw = (await self._odometry()).yaw
            turned += wrap_angle(yaw - last_yaw)  # unwrapped, so a full turn or more works
            last_yaw = yaw
            remaining = radians - turned
            if abs(remaining) <= ANGLE_TOLERANCE:
                break
            if time.monotonic() - began > timeout:
                return MotionResult(
                    "rotate",
                    "timed out",
                    f"turned {math.degrees(turned):.1f} of {math.degrees(radians):g} degrees in {timeout:.0f} s",
                    time.monotonic() - began,
                )
            angular = math.copysign(min(speed, max(MIN_ANGULAR, ANGULAR_GAIN * abs(remaining))), remaining)
            self.deadman.arm(time.monotonic() + HEARTBEAT)
            self._send_twist(0.0, angular)
            await asyncio.sleep(self.period)
        self._zero()
        direction = "left" if radians >= 0 else "right"
        detail = f"turned {abs(math.degrees(turned)):.1f} degrees {direction} (asked {abs(math.degrees(radians)):g})"
        return MotionResult("rotate", "done", detail, time.monotonic() - began)

    def _zero(self) -> None:
        """The stop every motion ends with; the watchdog stands down once it is sent."""
        try:
            self._send_twist(0.0, 0.0)
        except DeviceError:
            log.warning("%s: cannot send the zero twist: the robot is unreachable", self.instance)
            return  # leave the watchdog armed: it retries from its thread
        self.deadman.disarm()
