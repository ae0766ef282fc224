"""``search``: a long task that looks for a person, within a time limit and a distance from its start.

The pattern: at the start, turn in place in steps narrower than the camera's field of view,
taking a picture and running the people detector (:mod:`rosaos_ros.sightings`) after each
step, so one full turn sees all around. A sighting is confirmed by turning to face it and
looking again before the search ends. If nobody is found, drive to the next waypoint (a ring
of four around the start, then a wider ring turned 45 degrees, each within ``max_distance``)
and look around again, until someone is found, the time is up, or no waypoint is left.

Every move goes through the backend's ``rotate`` and ``move_distance``: the velocity limits, the
refusal while docked, the deadman and the emergency stop all apply as to any other motion. The
search stops at once when its tool call is cancelled, when ``stop`` or the emergency stop ends a
motion, or when its caller is gone (``alive`` says so: a process killed by ``terminate_process``).
"""

from __future__ import annotations

import inspect
import math
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rosaos.drivers import DeviceError

if TYPE_CHECKING:
    from rosaos_ros.backend import RosBackend

STEP_DEGREES = 45.0
"""Turn between two pictures: narrower than the 70 degree field of view, so views overlap."""
LOOK_TIMEOUT = 5.0
"""Seconds to wait for a camera frame."""
RING = 1.0
"""Metres: radius of the first ring of waypoints (less when max_distance is smaller)."""
CONFIRM_RADIUS = 1.0
"""Metres: a second sighting this close to the first is the same person."""
WAYPOINT_TIME = 3.0
"""Seconds a move to a waypoint is budgeted besides driving, before starting it."""

Progress = Callable[[float, str], Awaitable[None]]
"""``progress(seconds_elapsed, message)``."""


class SearchStopped(Exception):
    """A motion of the search was stopped (``stop``, the emergency stop): the search ends."""


@dataclass
class SearchRun:
    """One search, from its start pose."""

    backend: RosBackend
    max_seconds: float
    max_distance: float
    progress: Progress
    alive: Callable[[], Awaitable[bool]]
    started: float = field(default_factory=time.monotonic)
    pictures: int = 0
    travelled: float = 0.0
    start: tuple[float, float, float] = (0.0, 0.0, 0.0)
    last_image: str | None = None
    halted: str | None = None
    """Set by the emergency stop (or ``stop``): the search ends before its next move or picture."""

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self.started

    def _pose(self) -> tuple[float, float, float]:
        odometry = self.backend.state.latest_odometry()
        return odometry.x, odometry.y, odometry.yaw

    async def run(self) -> dict[str, Any]:
        """Search until found or out of time or places; returns the report (``found`` true or false)."""
        self.start = self._pose()
        try:
            for index, waypoint in enumerate([None, *self._waypoints()]):
                if waypoint is not None and not await self._go_to(waypoint, index):
                    break
                found = await self._look_around(index)
                if found is not None:
                    self.backend.notices.person_seen(found)
                    return self._report(True, "found a person", found)
                if self.elapsed >= self.max_seconds:
                    break
        except SearchStopped as stop:
            return self._report(False, f"stopped: {stop}", None)
        why = (
            "time is up"
            if self.elapsed >= self.max_seconds
            else "looked everywhere within the distance limit"
        )
        return self._report(False, f"nobody found ({why})", None)

    def _waypoints(self) -> list[tuple[float, float]]:
        x0, y0, yaw0 = self.start
        near = min(RING, self.max_distance / 2)
        points = []
        for radius, offset in ((near, 0.0), (min(2 * near, self.max_distance), math.pi / 4)):
            if radius < 0.2:
                continue
            for k in range(4):
                angle = yaw0 + offset + k * math.pi / 2
                points.append((x0 + radius * math.cos(angle), y0 + radius * math.sin(angle)))
        return points

    async def _go_to(self, target: tuple[float, float], index: int) -> bool:
        """Turn toward ``target`` and drive there; False when there is no time left to."""
        x, y, yaw = self._pose()
        distance = math.hypot(target[0] - x, target[1] - y)
        speed = min(self.backend.profile.speeds.linear, self.backend.limits.linear)
        if self.elapsed + distance / speed + WAYPOINT_TIME > self.max_seconds:
            return False
        await self._check_alive()
        await self.progress(self.elapsed, f"moving {distance:.1f} m to search spot {index + 1}")
        turn = math.degrees(math.atan2(target[1] - y, target[0] - x) - yaw)
        turn = (turn + 180) % 360 - 180
        await self._motion(self.backend.rotate(turn, None))
        await self._check_alive()
        before = self._pose()
        await self._motion(self.backend.move_distance(distance, None))
        after = self._pose()
        self.travelled += math.hypot(after[0] - before[0], after[1] - before[1])
        if math.hypot(after[0] - self.start[0], after[1] - self.start[1]) > self.max_distance + 0.1:
            raise SearchStopped("left the allowed distance from the start")
        return True

    async def _look_around(self, index: int) -> dict[str, Any] | None:
        """One full turn in steps, a picture after each; the nearest person seen, or None."""
        steps = math.ceil(360 / STEP_DEGREES)
        for step in range(steps):
            if self.elapsed >= self.max_seconds:
                return None
            await self._check_alive()
            if step:
                await self._motion(self.backend.rotate(STEP_DEGREES, None))
            result = await self.backend.detect_people(LOOK_TIMEOUT)
            self.pictures += 1
            self.last_image = result["image"]
            if result["people"]:
                person = min(result["people"], key=lambda person: person["distance_m"])
                confirmed = await self._confirm(person)
                if confirmed is not None:
                    return confirmed
            where = "the start" if index == 0 else f"search spot {index}"
            await self.progress(
                self.elapsed,
                f"looked {step + 1} of {steps} ways at {where}: nobody yet "
                f"({self.pictures} pictures, {self.elapsed:.0f} of {self.max_seconds:g} s)",
            )
        return None

    async def _confirm(self, person: dict[str, Any]) -> dict[str, Any] | None:
        """Turn to face a sighting and look again: a person is still there, a shadow or edge that
        fooled the detector from one angle seldom is. The second sighting, or None."""
        await self._check_alive()
        await self.progress(self.elapsed, f"maybe someone {person['direction']}; turning to look")
        await self._motion(self.backend.rotate(person["bearing_deg"], None))
        result = await self.backend.detect_people(LOOK_TIMEOUT)
        self.pictures += 1
        self.last_image = result["image"]
        for again in result["people"]:
            if "x" not in person or "x" not in again:
                return again
            if math.hypot(again["x"] - person["x"], again["y"] - person["y"]) < CONFIRM_RADIUS:
                return again
        return None

    async def _motion(self, motion: Awaitable[Any]) -> None:
        if self.halted:
            if inspect.iscoroutine(motion):
                motion.close()  # never started
            raise SearchStopped(self.halted)
        result = await motion
        if result.outcome == "stopped":
            raise SearchStopped(result.detail)
        if result.outcome == "timed out":
            raise DeviceError(f"{self.backend.instance}: the search could not move: {result.detail}")

    async def _check_alive(self) -> None:
        if self.halted:
            raise SearchStopped(self.halted)
        if not await self.alive():
            raise SearchStopped("the process that asked for the search is gone")

    def _report(self, found: bool, outcome: str, person: dict[str, Any] | None) -> dict[str, Any]:
        x, y, yaw = self._pose()
        report: dict[str, Any] = {"found": found, "outcome": outcome}
        if person is not None:
            report |= {
                key: person[key]
                for key in ("x", "y", "frame", "anchor", "distance_m", "bearing_deg", "direction")
                if key in person
            }
        report |= {
            "seconds": round(self.elapsed, 1),
            "pictures": self.pictures,
            "travelled_m": round(self.travelled, 2),
            "robot": {"x": round(x, 3), "y": round(y, 3), "yaw": round(yaw, 3)},
            "start": {"x": round(self.start[0], 3), "y": round(self.start[1], 3)},
            "image": self.last_image,
        }
        return report
