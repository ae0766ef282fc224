"""Where the robot is, in which frame, and ``go_to``: a pose on the map (Nav2) or on odometry.

A pose means nothing without its frame, and a frame name is not enough: ``odom`` is wherever
the robot booted, and ``map`` is whichever map it localizes on. So :meth:`Navigator.pose` reports
a **frame anchor** with every pose, and ``go_to`` refuses a goal whose anchor is not the current
one (a place saved before a restart, on another map, or in another odometry session):

- with Nav2 (the profile's ``navigation``), poses come from localization (AMCL's ``/amcl_pose``)
  in the map frame, anchored to the map's file name (``/map_server:yaml_filename``): places
  survive restarts and odometry resets, and robots on the same map share them;
- without it, poses are odometry, anchored to this driver run: odometry restarts where the robot
  boots, and nothing on the robot says whether it did, so an odometry pose is never trusted
  after the driver restarts.

``go_to`` with Nav2 sends ``NavigateToPose`` (feedback streams as progress; ``stop`` and
``safe_stop`` cancel it, as they cancel every goal). Without Nav2 it turns toward the goal,
drives straight to it and turns to the heading, closed loop on odometry, avoiding nothing.
"""

from __future__ import annotations

import asyncio
import math
import time
import uuid
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosaos.drivers import DeviceError
from rosaos_ros.bridge import Message
from rosaos_ros.goals import FeedbackCallback
from rosaos_ros.messages import quaternion_from_yaw, wrap_angle, yaw_from_quaternion
from rosaos_ros.safety import Refused

if TYPE_CHECKING:
    from rosaos_ros.backend import RosBackend

MAP_POSE_MAX_AGE = 5.0
"""Seconds: a map pose older than this means localization is not running."""
MAP_POSE_WAIT = 3.0
"""How long a fresh connection waits for localization's first pose before calling the robot lost.
The pose topic ticks more slowly than odometry, so its first message can come after odometry's."""
ARRIVED = 0.05
"""Metres: on odometry, closer than this to the goal needs no drive."""


@dataclass(frozen=True)
class FramedPose:
    """A pose and the frame it is in; ``anchor`` names that frame's instance (see the module docstring)."""

    x: float
    y: float
    yaw: float
    frame: str
    anchor: str

    def as_dict(self) -> dict[str, Any]:
        return {
            "x": round(self.x, 4),
            "y": round(self.y, 4),
            "yaw": round(self.yaw, 4),
            "frame": self.frame,
            "anchor": self.anchor,
        }


class Navigator:
    """The pose in its frame, and ``go_to``, for one robot."""

    def __init__(self, backend: RosBackend) -> None:
        self.backend = backend
        self.session = uuid.uuid4().hex[:12]
        """This driver run's odometry session: the odometry anchor."""
        self._map_pose: tuple[float, float, float, float] | None = None  # x, y, yaw, received
        self._map_name: str | None = None

    def start(self) -> None:
        """Subscribe to the localization pose, if the robot navigates on a map."""
        navigation = self.backend.profile.navigation
        if navigation is not None:
            self.backend.bridge.subscribe(navigation.pose.topic, navigation.pose.type, self._on_map_pose)

    def _on_map_pose(self, msg: Message) -> None:
        try:
            pose = msg["pose"]["pose"]
            x, y = float(pose["position"]["x"]), float(pose["position"]["y"])
            yaw = yaw_from_quaternion(pose["orientation"])
        except (KeyError, TypeError, ValueError):
            return
        self._map_pose = (x, y, yaw, time.monotonic())

    async def pose(self) -> FramedPose:
        """Where the robot is now, in the frame places are stored in."""
        backend = self.backend
        navigation = backend.profile.navigation
        if navigation is None:
            if backend.state.odometry is None:  # a fresh connection: odometry's first message
                await backend.state.wait_for_messages(sources={"odom"})
            odometry = backend.state.latest_odometry()
            anchor = f"odom:{backend.instance}:{self.session}"
            return FramedPose(odometry.x, odometry.y, odometry.yaw, "odom", anchor)
        if self._map_pose is None:
            await backend.state.wait_for_messages(sources={"odom"})
            deadline = time.monotonic() + MAP_POSE_WAIT
            # Polled, not an asyncio.Event: the pose callback may run on the bridge's own thread.
            while self._map_pose is None and time.monotonic() < deadline:  # noqa: ASYNC110
                await asyncio.sleep(0.05)
        if self._map_pose is None or time.monotonic() - self._map_pose[3] > MAP_POSE_MAX_AGE:
            raise DeviceError(
                f"{backend.instance}: no pose on {navigation.pose.topic}: the robot is not localized on a map; "
                "start localization (Nav2's AMCL) and set its initial pose"
            )
        x, y, yaw, _ = self._map_pose
        return FramedPose(x, y, yaw, navigation.frame, await self._map_anchor())

    async def _map_anchor(self) -> str:
        navigation = self.backend.profile.navigation
        assert navigation is not None
        if self._map_name is None:
            self._map_name = ""
            if navigation.map_param:
                try:
                    self._map_name = str(await self.backend.rosapi.get_param(navigation.map_param))
                except DeviceError:
                    self._map_name = ""  # no map server parameter: one unnamed map
        return f"{navigation.frame}:{self._map_name}" if self._map_name else navigation.frame

    async def go_to(
        self, x: float, y: float, yaw: float | None, anchor: str | None, on_feedback: FeedbackCallback | None
    ) -> dict[str, Any]:
        """Drive to (x, y) and turn to ``yaw`` (radians, if given); refuse a goal of another frame."""
        backend = self.backend
        here = await self.pose()
        if anchor is not None and anchor != here.anchor:
            raise Refused(_other_frame(backend.instance, anchor, here))
        navigation = backend.profile.navigation
        if navigation is not None:
            backend.policy.check("actions", navigation.action)
        await backend.check_may_move()
        await backend.motion.stop("replaced by go_to")
        if navigation is None:
            report = await self._go_on_odometry(here, x, y, yaw)
        else:
            goal = {
                "pose": {
                    "header": {"frame_id": navigation.frame},
                    "pose": {
                        "position": {"x": x, "y": y, "z": 0.0},
                        # No heading asked: arrive facing the way the robot drove.
                        "orientation": quaternion_from_yaw(
                            yaw if yaw is not None else math.atan2(y - here.y, x - here.x)
                        ),
                    },
                },
                "behavior_tree": "",
            }
            record = await backend.goals.send(
                navigation.action, navigation.type, goal, timeout=navigation.timeout, on_feedback=on_feedback
            )
            report = record.as_dict()
            if record.status != "succeeded":
                detail = record.error or _result_error(record.result) or record.status
                raise DeviceError(f"{backend.instance}: did not reach ({x:g}, {y:g}): {detail}")
        await backend.state.settle()
        arrived = await self.pose()
        return {
            "arrived": True,
            "goal": {"x": x, "y": y, "yaw": yaw, "frame": here.frame},
            "pose": arrived.as_dict(),
            "error_m": round(math.hypot(arrived.x - x, arrived.y - y), 3),
            "navigation": report,
        }

    async def _go_on_odometry(
        self, here: FramedPose, x: float, y: float, yaw: float | None
    ) -> dict[str, Any]:
        """Turn toward the goal, drive straight to it, turn to ``yaw``: three closed-loop motions."""
        motion, speeds, limits = self.backend.motion, self.backend.profile.speeds, self.backend.limits
        linear, angular = min(speeds.linear, limits.linear), min(speeds.angular, limits.angular)
        distance = math.hypot(x - here.x, y - here.y)
        steps = []
        if distance > ARRIVED:
            bearing = math.atan2(y - here.y, x - here.x)
            steps.append(await motion.rotate(wrap_angle(bearing - here.yaw), angular))
            if steps[-1].outcome == "done":
                steps.append(await motion.move_distance(distance, linear))
        if yaw is not None and all(step.outcome == "done" for step in steps):
            now = await self.pose()
            steps.append(await motion.rotate(wrap_angle(yaw - now.yaw), angular))
        unfinished = next((step for step in steps if step.outcome != "done"), None)
        if unfinished is not None:
            raise DeviceError(f"{self.backend.instance}: go_to {unfinished.outcome}: {unfinished.detail}")
        return {
            "planner": "straight line on odometry (no obstacle avoidance)",
            "steps": [s.as_dict() for s in steps],
        }


def _other_frame(instance: str, anchor: str, here: FramedPose) -> str:
    """Why a goal saved in another frame is refused, and what to do about it."""
    if anchor.startswith("odom:"):
        why = (
            "it was saved on odometry in an earlier session; odometry starts over where the robot boots, "
            "so those coordinates now name a different spot"
        )
    elif here.frame == "odom":
        why = f"it was saved on a map ({anchor}), and {instance} has no map localization now"
    else:
        why = f"it was saved on another map ({anchor}); {instance} is on {here.anchor}"
    return (
        f"refused: {instance} will not drive there: {why}. Stand the robot at the spot and save it again, "
        "or give the coordinates in the current frame"
    )


def _result_error(result: Any) -> str:
    if isinstance(result, dict):
        return str(result.get("error_msg") or "")
    return ""
