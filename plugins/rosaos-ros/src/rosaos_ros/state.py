"""The robot's state as ``get_state`` reports it, kept from persistent topic subscriptions.

Pose and velocities come from odometry (``x``, ``y`` metres, ``yaw`` radians in (-pi, pi],
``linear`` m/s, ``angular`` rad/s); the profile's ``state`` mapping adds keys read from fields
of other topics (``docked`` from /dock_status, ``battery`` from /battery_state on a TurtleBot 4).
"""

from __future__ import annotations

import asyncio
import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from rosaos.drivers import DeviceError
from rosaos_ros.bridge import Message, RosbridgeClient
from rosaos_ros.messages import yaw_from_quaternion
from rosaos_ros.profiles import Profile

FIRST_MESSAGE_WAIT = 1.5
"""Seconds get_state waits, after (re)connecting, for the first message of each state topic."""
SETTLE = 0.03
"""Seconds after a stop before odometry can show it (the zero twist's trip and one base tick)."""
ODOMETRY_STALE = 2.0
"""Odometry older than this means the base driver is not running: get_state says so."""


@dataclass(frozen=True)
class Odometry:
    """The latest odometry, and when it arrived (monotonic seconds)."""

    x: float
    y: float
    yaw: float
    linear: float
    angular: float
    received: float

    @classmethod
    def from_message(cls, msg: Message) -> Odometry:
        pose = msg["pose"]["pose"]
        twist = msg["twist"]["twist"]
        return cls(
            x=float(pose["position"]["x"]),
            y=float(pose["position"]["y"]),
            yaw=yaw_from_quaternion(pose["orientation"]),
            linear=float(twist["linear"]["x"]),
            angular=float(twist["angular"]["z"]),
            received=time.monotonic(),
        )

    @property
    def age(self) -> float:
        return time.monotonic() - self.received


class RobotStateCache:
    """Subscribes to the profile's odometry and state topics and keeps their latest values."""

    def __init__(self, bridge: RosbridgeClient, profile: Profile) -> None:
        self.bridge = bridge
        self.profile = profile
        self.odometry: Odometry | None = None
        self.fields: dict[str, Any] = {}
        self._seen: dict[str, float] = {}
        """When each source (``odom`` and every state key) last sent a message, monotonic."""
        self._waiters: list[asyncio.Future[None]] = []
        self._unsubscribe: list[Callable[[], None]] = []
        self.on_field: Callable[[str, Any], None] | None = None
        """Called with (key, value) for every state message (the driver's notices watch it)."""

    def start(self) -> None:
        """Subscribe (roslibpy re-subscribes by itself after a reconnection)."""
        odom = self.profile.odom
        if odom is not None:
            self._unsubscribe.append(self.bridge.subscribe(odom.topic, odom.type, self._on_odometry))
        for key, field in self.profile.state.items():
            self._unsubscribe.append(
                self.bridge.subscribe(field.topic, field.type, self._field_setter(key, field.field))
            )

    def stop(self) -> None:
        """Unsubscribe from everything."""
        for unsubscribe in self._unsubscribe:
            unsubscribe()
        self._unsubscribe.clear()

    def _on_odometry(self, msg: Message) -> None:
        try:
            self.odometry = Odometry.from_message(msg)
        except (KeyError, TypeError, ValueError):
            return  # not an Odometry after all: get_state reports no odometry
        self._saw("odom")

    def _field_setter(self, key: str, path: str) -> Callable[[Message], None]:
        def update(msg: Message) -> None:
            value: Any = msg
            for part in path.split("."):
                value = value.get(part) if isinstance(value, dict) else None
            self.fields[key] = round(value, 4) if isinstance(value, float) else value
            self._saw(key)
            if self.on_field is not None:
                self.on_field(key, self.fields[key])

        return update

    def _sources(self) -> set[str]:
        return set(self.profile.state) | ({"odom"} if self.profile.odom is not None else set())

    def _saw(self, source: str) -> None:
        self._seen[source] = time.monotonic()
        waiters, self._waiters = self._waiters, []
        for waiter in waiters:
            if not waiter.done():
                waiter.set_result(None)

    async def wait_for_messages(self, since: float = -math.inf, sources: set[str] | None = None) -> None:
        """Wait (up to :data:`FIRST_MESSAGE_WAIT`) until every source has sent a message after ``since``.

        ``sources``: ``odom`` and state keys; default all. Missing sources are not an error (their
        keys read null); a lost connection is.
        """
        wanted = self._sources() if sources is None else self._sources() & sources

        await self._wait_until(
            lambda: all(self._seen.get(source, -math.inf) > since for source in wanted), FIRST_MESSAGE_WAIT
        )

    def latest_odometry(self, max_age: float = ODOMETRY_STALE) -> Odometry:
        """The latest odometry; :class:`DeviceError` if there is none or it is stale."""
        odom = self.profile.odom
        if odom is None:
            raise DeviceError(
                f"{self.bridge.instance}: the {self.profile.name} profile has no odometry topic, "
                "so the robot cannot tell where it is"
            )
        if self.odometry is None:
            raise DeviceError(
                f"{self.bridge.instance}: no odometry on {odom.topic} yet; is the robot's base driver running?"
            )
        if self.odometry.age > max_age:
            raise DeviceError(
                f"{self.bridge.instance}: no odometry on {odom.topic} for {self.odometry.age:.1f} s; "
                "the robot's base driver may be down"
            )
        return self.odometry

    async def refresh(self) -> None:
        """Wait for a new message on every state topic, e.g. after an undock.

        So the next get_state, or the next motion refused while ``docked``, sees the robot as it
        is now and not as it was a moment before the action ended.
        """
        await self.wait_for_messages(since=time.monotonic())

    async def wait_for_fields(self, expected: dict[str, Any], timeout: float) -> None:
        """Wait (up to ``timeout`` s) until every state key in ``expected`` shows its value.

        A named action's status topic may still carry the old value for a message or two after
        the action ended, and on a busy machine longer than :meth:`refresh` waits. Past the
        timeout the state is read as it is: get_state then tells the truth, and a motion refused
        while ``docked`` says so.
        """

        await self._wait_until(
            lambda: all(self.fields.get(key) == value for key, value in expected.items()), timeout
        )

    async def _wait_until(self, done: Callable[[], bool], timeout: float) -> None:
        """Wait for state messages until ``done()``; a timeout is not an error, a lost connection is."""

        async def wait() -> None:
            while not done():
                waiter = asyncio.get_running_loop().create_future()
                self._waiters.append(waiter)
                await waiter

        if done():
            return
        try:
            await self.bridge.guarded(wait(), timeout, "state topics")
        except DeviceError:
            if not self.bridge.connected:
                raise

    async def settle(self) -> None:
        """Wait for odometry sent after the robot was told to stop, so the state shows it at rest."""
        await self.wait_for_messages(since=time.monotonic() + SETTLE, sources={"odom"})

    async def snapshot(self) -> dict[str, Any]:
        """The ``get_state`` object: pose and velocities, then the profile's state keys."""
        self.bridge.check()
        await self.wait_for_messages()
        state: dict[str, Any] = {}
        if self.profile.odom is not None:
            odometry = self.latest_odometry()
            state.update(
                x=round(odometry.x, 4),
                y=round(odometry.y, 4),
                yaw=round(odometry.yaw, 4),
                linear=round(odometry.linear, 4),
                angular=round(odometry.angular, 4),
            )
        for key in self.profile.state:
            state[key] = self.fields.get(key)
        return state
