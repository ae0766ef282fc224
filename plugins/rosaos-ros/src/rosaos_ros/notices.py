"""The ROS driver's device notices: battery low, docked and undocked, a person seen in a search.

Declared in :data:`NOTICES` (the DriverSpec's ``notices``) and posted through the instance's
``DeviceContext.notify`` (the kernel fetches them, rate-limited and deduplicated). State notices
fire on a change seen on the robot's own topics, never on the first value after connecting, so
a restart does not announce that a docked robot is docked.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from pydantic import BaseModel, Field

from rosaos.drivers import NoticeSpec

BATTERY_LOW = 0.2
"""Below this share of charge the robot says its battery is low."""
BATTERY_OK = 0.25
"""Above this the low-battery notice is armed again (a hysteresis, so a battery hovering at the
threshold is announced once)."""


class BatteryLow(BaseModel):
    """The charge when it went low."""

    battery: float = Field(ge=0, le=1)


class PersonSeen(BaseModel):
    """Where a search found someone (odometry frame, metres)."""

    x: float
    y: float
    distance_m: float = Field(ge=0)


NOTICES = {
    "battery_low": NoticeSpec(
        description=f"The battery fell under {BATTERY_LOW:.0%}: dock the robot soon",
        importance="notify",
        data=BatteryLow,
        example={"battery": 0.18},
    ),
    "docked": NoticeSpec(description="The robot is on its charging dock"),
    "undocked": NoticeSpec(description="The robot left its charging dock"),
    "person_seen": NoticeSpec(
        description="A search found a person",
        importance="notify",
        data=PersonSeen,
        example={"x": -2.5, "y": 0.5, "distance_m": 2.4},
    ),
}

Notify = Callable[..., Any]


class RobotNotices:
    """Turns state changes and search results into notices for one instance."""

    def __init__(self, instance: str, notify: Notify | None) -> None:
        self.instance = instance
        self._notify = notify
        self._last: dict[str, Any] = {}
        self._battery_armed = True

    def field_changed(self, key: str, value: Any) -> None:
        """A state topic gave ``key`` the value ``value`` (called for every message)."""
        previous, self._last[key] = self._last.get(key), value
        if key == "docked" and isinstance(value, bool) and isinstance(previous, bool) and value != previous:
            where = "is back on its dock" if value else "left its dock"
            self._post("docked" if value else "undocked", None, f"{self.instance} {where}")
        elif key == "battery" and isinstance(value, int | float):
            if value >= BATTERY_OK:
                self._battery_armed = True
            elif value < BATTERY_LOW and self._battery_armed and previous is not None:
                self._battery_armed = False
                self._post(
                    "battery_low",
                    {"battery": round(float(value), 3)},
                    f"{self.instance}'s battery is at {value:.0%}",
                )

    def person_seen(self, person: dict[str, Any]) -> None:
        """A search found ``person`` (a detect_people entry with x, y)."""
        if "x" not in person or "y" not in person:
            return
        data = {"x": person["x"], "y": person["y"], "distance_m": person["distance_m"]}
        self._post(
            "person_seen",
            data,
            f"{self.instance} found a person {person['distance_m']:.1f} m away, at x {person['x']:.1f}, y {person['y']:.1f}",
        )

    def _post(self, name: str, data: dict[str, Any] | None, message: str) -> None:
        if self._notify is not None:
            self._notify(name, data, message=message)
