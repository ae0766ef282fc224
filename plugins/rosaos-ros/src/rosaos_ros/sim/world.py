"""The simulated robot's physics: a differential-drive base on a flat floor, a dock, a battery.

Pure and synchronous, so it is easy to test: :meth:`DiffDriveWorld.step` advances time by ``dt``.
The base follows the last velocity command exactly (no acceleration limit, so closed-loop tests
are deterministic) within its hardware limits, and stops when commands stop arriving for
``cmd_timeout`` seconds, as real bases do (the Create 3 uses 0.5 s).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Annotated, Any, Protocol

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from rosaos_ros.messages import wrap_angle
from rosaos_ros.profiles import Limits

CMD_TIMEOUT = 0.5
"""Seconds of /cmd_vel silence after which the simulated base stops."""
DOCK_RADIUS = 0.05
"""Metres from the dock pose within which the robot can be docked; further away it is not."""
BATTERY_IDLE_DRAIN = 0.00003  # per second: about 10 % in an hour of standing
BATTERY_MOVING_DRAIN = 0.0001  # per second, on top, while the wheels turn
BATTERY_CHARGE_RATE = 0.0003  # per second on the dock: about an hour from empty


class DockPose(BaseModel):
    """Where the charging dock is: the pose a docked robot has."""

    model_config = ConfigDict(extra="forbid")

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0


class PersonSpot(BaseModel):
    """Where a simulated person stands (metres, world frame); the camera shows them when in view."""

    model_config = ConfigDict(extra="forbid")

    x: float
    y: float


class SimState(BaseModel):
    """The simulator's initial state: the ``sim`` table of an instance (keys as ``get_state`` has them).

    ``profile`` picks the simulated robot; ``dock`` places its dock (default: where a docked robot
    starts, else the origin); ``people`` stand where the camera can see them. Velocities must be 0:
    a simulated robot starts at rest.
    """

    model_config = ConfigDict(extra="forbid")

    profile: str | None = None
    x: float = 0.0
    y: float = 0.0
    yaw: Annotated[float, Field(ge=-math.pi, le=math.pi)] = 0.0
    linear: float = 0.0
    angular: float = 0.0
    docked: bool = False
    battery: Annotated[float, Field(ge=0, le=1)] = 0.9
    dock: DockPose | None = None
    odom_origin: DockPose | None = None
    """Where odometry starts, in the world (map) frame; default the world's origin. A real base
    starts its odometry where it boots: change this to model a robot that booted elsewhere."""
    people: Annotated[list[PersonSpot], Field(max_length=50)] = Field(default_factory=list)

    @field_validator("linear", "angular")
    @classmethod
    def _at_rest(cls, value: float) -> float:
        if value != 0:
            raise ValueError("a simulated robot starts at rest: use 0, then drive it with the tools")
        return value

    @model_validator(mode="after")
    def _docked_means_on_the_dock(self) -> SimState:
        if self.docked and self.dock is not None:
            gap = math.hypot(self.x - self.dock.x, self.y - self.dock.y)
            if gap > DOCK_RADIUS:
                raise ValueError(
                    f"docked is true but the robot is {gap:.2f} m from the dock pose; move one of them"
                )
        return self


class Pilot(Protocol):
    """Something that drives the base by itself (docking, navigation) instead of /cmd_vel."""

    def command(self, world: DiffDriveWorld) -> tuple[float, float] | None:
        """The twist to apply now, or None once it is done."""
        ...


@dataclass
class Autopilot:
    """Drives the base to a pose by itself (docking): turn, drive straight, turn to the final heading.

    It backs up when the target is behind, as the Create 3 does onto its dock, unless
    ``forward_only`` (a navigation leg: it turns to face the target first).
    """

    x: float
    y: float
    yaw: float
    speed: float
    turn_speed: float
    phase: str = "align"
    forward_only: bool = False

    def command(self, world: DiffDriveWorld) -> tuple[float, float] | None:
        """The twist to apply now, or None once the target pose is reached."""
        dx, dy = self.x - world.x, self.y - world.y
        distance = math.hypot(dx, dy)
        if self.phase in ("align", "drive") and distance < 0.01:
            self.phase = "turn"
        if self.phase == "turn":
            error = wrap_angle(self.yaw - world.yaw)
            if abs(error) < math.radians(1):
                return None
            return 0.0, _toward(error, self.turn_speed)
        bearing = math.atan2(dy, dx)
        reverse = not self.forward_only and abs(wrap_angle(bearing - world.yaw)) > math.pi / 2
        heading = wrap_angle(bearing + math.pi) if reverse else bearing
        error = wrap_angle(heading - world.yaw)
        if self.phase == "align":
            if abs(error) > math.radians(3):
                return 0.0, _toward(error, self.turn_speed)
            self.phase = "drive"
        speed = min(self.speed, max(0.03, 3.0 * distance))
        return (-speed if reverse else speed), _toward(error, self.turn_speed, gain=3.0)


def _toward(error: float, limit: float, gain: float = 4.0) -> float:
    """A proportional turn rate toward ``error`` radians, at most ``limit``, fast enough to finish."""
    rate = gain * error
    floor = 0.15 if abs(error) > math.radians(0.5) else 0.0
    return math.copysign(min(limit, max(floor, abs(rate))), error)


@dataclass
class DiffDriveWorld:
    """The state of the simulated base, advanced by :meth:`step`."""

    hardware_limits: Limits
    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0
    docked: bool = False
    battery: float = 0.9
    dock: DockPose = field(default_factory=DockPose)
    odom_origin: DockPose = field(default_factory=DockPose)
    cmd_timeout: float = CMD_TIMEOUT
    linear: float = 0.0
    """Actual forward speed, m/s."""
    angular: float = 0.0
    """Actual yaw rate, rad/s (positive: counter-clockwise)."""
    e_stop: bool = False
    autopilot: Pilot | None = None
    commanded: tuple[float, float] = (0.0, 0.0)
    last_command_at: float = -math.inf
    stopped_by: str = "start"
    """Why the base last came to rest: "zero twist", "cmd_vel timeout", "e_stop", "autopilot"."""
    commands: deque[tuple[float, float, float]] = field(default_factory=lambda: deque(maxlen=5000))
    """Every velocity command received: (monotonic time, linear, angular). For tests."""
    people: list[tuple[float, float]] = field(default_factory=list)
    """Where people stand (x, y), for the camera."""
    extra_messages: dict[str, dict[str, Any]] = field(default_factory=dict)
    """The last message on each extra topic (light ring, audio). For tests."""

    @classmethod
    def from_state(cls, state: SimState, hardware_limits: Limits) -> DiffDriveWorld:
        """A world in the initial state ``state``; the dock is where a docked robot starts, else the origin."""
        dock = state.dock or (DockPose(x=state.x, y=state.y, yaw=state.yaw) if state.docked else DockPose())
        return cls(
            hardware_limits=hardware_limits,
            x=state.x,
            y=state.y,
            yaw=wrap_angle(state.yaw),
            docked=state.docked,
            battery=state.battery,
            dock=dock,
            odom_origin=state.odom_origin or DockPose(),
            people=[(person.x, person.y) for person in state.people],
        )

    def command(self, linear: float, angular: float, now: float) -> None:
        """A velocity command arrived on /cmd_vel at monotonic time ``now``."""
        self.commands.append((now, linear, angular))
        self.commanded = (linear, angular)
        self.last_command_at = now
        if linear == 0 and angular == 0 and (self.linear or self.angular):
            self.stopped_by = "zero twist"

    def step(self, dt: float, now: float) -> None:
        """Advance the world by ``dt`` seconds, ending at monotonic time ``now``."""
        linear, angular = self._twist(now)
        limits = self.hardware_limits
        linear = max(-limits.linear, min(limits.linear, linear))
        angular = max(-limits.angular, min(limits.angular, angular))
        if abs(angular) < 1e-9:
            self.x += linear * math.cos(self.yaw) * dt
            self.y += linear * math.sin(self.yaw) * dt
        else:  # exact arc for a constant twist over dt
            radius = linear / angular
            new_yaw = self.yaw + angular * dt
            self.x += radius * (math.sin(new_yaw) - math.sin(self.yaw))
            self.y -= radius * (math.cos(new_yaw) - math.cos(self.yaw))
        self.yaw = wrap_angle(self.yaw + angular * dt)
        self.linear, self.angular = linear, angular
        if self.docked and math.hypot(self.x - self.dock.x, self.y - self.dock.y) > DOCK_RADIUS:
            self.docked = False
        self._battery(dt)

    def _twist(self, now: float) -> tuple[float, float]:
        if self.e_stop:
            self._rest("e_stop")
            return 0.0, 0.0
        if self.autopilot is not None:
            twist = self.autopilot.command(self)
            if twist is not None:
                return twist
            self.autopilot = None
            self._rest("autopilot")
            return 0.0, 0.0
        if now - self.last_command_at > self.cmd_timeout:
            if self.commanded != (0.0, 0.0):
                self.commanded = (0.0, 0.0)
                self._rest("cmd_vel timeout")
            return 0.0, 0.0
        return self.commanded

    def _rest(self, reason: str) -> None:
        if self.linear or self.angular:
            self.stopped_by = reason

    def _battery(self, dt: float) -> None:
        if self.docked:
            self.battery = min(1.0, self.battery + BATTERY_CHARGE_RATE * dt)
            return
        moving = BATTERY_MOVING_DRAIN if (self.linear or self.angular) else 0.0
        self.battery = max(0.0, self.battery - (BATTERY_IDLE_DRAIN + moving) * dt)

    def on_dock_pose(self) -> bool:
        """True when the robot sits on the dock pose (within 2 cm and 3 degrees)."""
        return math.hypot(self.x - self.dock.x, self.y - self.dock.y) < 0.02 and abs(
            wrap_angle(self.yaw - self.dock.yaw)
        ) < math.radians(3)

    def dock_in_sight(self) -> bool:
        """Whether the dock's IR beacon would be seen: within 1.5 m."""
        return math.hypot(self.x - self.dock.x, self.y - self.dock.y) < 1.5

    def odometry_pose(self) -> tuple[float, float, float]:
        """The pose as odometry reports it: relative to :attr:`odom_origin`."""
        origin = self.odom_origin
        dx, dy = self.x - origin.x, self.y - origin.y
        cos, sin = math.cos(origin.yaw), math.sin(origin.yaw)
        return dx * cos + dy * sin, -dx * sin + dy * cos, wrap_angle(self.yaw - origin.yaw)

    def reset_pose(self, x: float, y: float, yaw: float) -> None:
        """Odometry reset (the ``reset_pose`` service): the robot is told where it is."""
        self.x, self.y, self.yaw = x, y, wrap_angle(yaw)
