"""The ``ros`` backend: one robot over rosbridge, with the safety rules between the tools and it.

:class:`RosBackend` composes the parts, each in its own module: the rosbridge connection
(:mod:`~rosaos_ros.bridge`), introspection (:mod:`~rosaos_ros.rosapi`), the state cache
(:mod:`~rosaos_ros.state`), motion with its deadman (:mod:`~rosaos_ros.motion`,
:mod:`~rosaos_ros.deadman`), action goals (:mod:`~rosaos_ros.goals`) and the rules
(:mod:`~rosaos_ros.safety`). Its methods are what the tools call; every one that changes the
robot passes a rule first. The ``real`` and ``sim`` backends are the same class: the ``sim`` one
also starts the rosbridge simulator in a thread and connects to it over a real socket.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

from PIL.Image import Image as PILImage

from rosaos.drivers import DeviceBackend, DeviceError
from rosaos_ros import camera
from rosaos_ros.bridge import RosbridgeClient
from rosaos_ros.deadman import DeadmanWatchdog
from rosaos_ros.goals import FeedbackCallback, GoalTracker
from rosaos_ros.messages import COMPRESSED_IMAGE, IMAGE, normalize_type, summarize, twist, twist_speeds
from rosaos_ros.motion import MotionController, MotionResult
from rosaos_ros.navigation import Navigator
from rosaos_ros.notices import Notify, RobotNotices
from rosaos_ros.profiles import Profile
from rosaos_ros.rosapi import Rosapi
from rosaos_ros.safety import AccessPolicy, Refused, VelocityLimits
from rosaos_ros.search import Progress, SearchRun
from rosaos_ros.settings import RosSettings
from rosaos_ros.sightings import Sightings
from rosaos_ros.sim import SimulatorError, SimulatorThread
from rosaos_ros.state import RobotStateCache

RAW_TWIST_LIFETIME = 0.5
STATE_SETTLE_WAIT = 5.0
"""Seconds a named action waits for the state topics to show what it left (``docked`` false)."""
"""Seconds a single raw velocity message (``publish`` on the velocity topic) may last."""
VELOCITY_HINT = (
    "To move the robot use drive, move_distance or rotate: they keep the velocity limits and the deadman."
)


class RosBackend(DeviceBackend):
    """One ROS 2 robot reached through rosbridge."""

    def __init__(
        self,
        instance: str,
        settings: RosSettings,
        profile: Profile,
        images_dir: Path,
        simulator: SimulatorThread | None = None,
        notify: Notify | None = None,
    ) -> None:
        self.instance = instance
        self.settings = settings
        self.profile = profile
        self.images_dir = images_dir
        self.simulator = simulator
        self.simulated = simulator is not None
        self.policy = AccessPolicy.build(instance, profile, settings)
        self.limits = VelocityLimits.build(instance, profile, settings)
        token = settings.rosbridge_token.get_secret_value() if settings.rosbridge_token else None
        self.bridge = RosbridgeClient(
            instance,
            settings.host,
            settings.rosbridge_port,
            secure=settings.secure,
            token=token,
            call_timeout=settings.call_timeout,
        )
        self.rosapi = Rosapi(self.bridge)
        self.state = RobotStateCache(self.bridge, profile)
        self.goals = GoalTracker(self.bridge)
        self.deadman = DeadmanWatchdog(self._send_zero_from_thread, name=f"rosaos-ros-deadman-{instance}")
        self.motion = MotionController(
            instance, self._send_twist, self.state, self.deadman, self.limits.angular / 2
        )
        self.bridge.on_disconnect(self.motion.abort)
        self.navigator = Navigator(self)
        self.sightings = Sightings(settings.camera_fov)
        self.notices = RobotNotices(instance, notify)
        self.state.on_field = self.notices.field_changed
        self.last_image: str | None = None
        self.search_run: SearchRun | None = None
        """The running search, so the emergency stop can end it."""
        """The latest picture's path, relative to the images directory (``get_state``'s ``last_image``)."""

    # Lifecycle

    async def start(self) -> None:
        """Start the simulator (sim backend), connect, and subscribe to the state topics."""
        if self.simulator is not None:
            try:
                await asyncio.to_thread(self.simulator.start)
            except SimulatorError as error:
                raise DeviceError(
                    f"{self.instance}: the rosbridge simulator did not start: {error}"
                ) from None
            self.bridge.host, self.bridge.port = self.simulator.simulator.host, self.simulator.simulator.port
        await self.bridge.connect(self.settings.connect_timeout)
        self.bridge.advertise(
            self.profile.cmd_vel.topic, self.profile.cmd_vel.type
        )  # before the watchdog needs it
        self.state.start()
        self.navigator.start()

    async def close(self) -> None:
        """Stop the robot, cancel goals, disconnect, stop the simulator."""
        with contextlib.suppress(DeviceError):
            await self.motion.stop("the driver is shutting down")
        await self.goals.close()
        self.state.stop()
        self.deadman.close()
        await self.bridge.close()
        if self.simulator is not None:
            await asyncio.to_thread(self.simulator.stop)

    async def safe_stop(self) -> dict[str, Any]:
        """Emergency stop: zero velocity, end the running search and motion, cancel every running goal."""
        if self.search_run is not None:
            self.search_run.halted = "emergency stop or stop"
        cancelled = self.goals.cancel_all()
        await self.motion.stop("emergency stop")
        self._send_twist(0.0, 0.0)  # raises when unreachable: the caller must know the stop did not land
        return {"stopped": True, "cancelled_goals": cancelled}

    def _send_twist(self, linear: float, angular: float) -> None:
        cmd_vel = self.profile.cmd_vel
        self.bridge.publish(cmd_vel.topic, cmd_vel.type, twist(linear, angular, cmd_vel.type))

    def _send_zero_from_thread(self) -> None:
        self._send_twist(0.0, 0.0)

    # State and camera

    async def get_state(self) -> dict[str, Any]:
        """Pose, velocities and the profile's state keys; the last picture and the people seen, once any."""
        state = {**await self.state.snapshot(), "profile": self.profile.name, **self.sightings.state()}
        if self.last_image is not None:
            state["last_image"] = self.last_image
        return state

    async def capture_image(self, timeout: float) -> dict[str, Any]:
        """One camera frame saved as JPEG in the images directory; returns its relative path."""
        report, _ = await self.capture_frame(timeout)
        return report

    async def capture_frame(self, timeout: float) -> tuple[dict[str, Any], PILImage]:
        """:meth:`capture_image`, also returning the decoded frame (for a model that takes images)."""
        topic = self.settings.camera_topic or (self.profile.camera.topic if self.profile.camera else None)
        if topic is None:
            raise DeviceError(
                f"{self.instance}: the {self.profile.name} profile has no camera; "
                f'set camera_topic = "/your/image_topic" in [devices.{self.instance}]'
            )
        known = self.profile.camera
        msg_type = (
            known.type
            if known is not None and known.topic == topic
            else await self.rosapi.require_topic_type(topic)
        )
        if normalize_type(msg_type) not in (IMAGE, COMPRESSED_IMAGE):
            raise DeviceError(
                f"{self.instance}: {topic} carries {msg_type}, not images; set camera_topic to an image topic"
            )
        frames = await self.bridge.collect(topic, msg_type, count=1, duration=timeout)
        if not frames:
            raise DeviceError(
                f"{self.instance}: no frame on {topic} within {timeout:g} s; is the camera driver running? "
                "(list_topics shows the image topics; set camera_topic to another one)"
            )
        image = await asyncio.to_thread(camera.decode, msg_type, frames[0])
        relative = await asyncio.to_thread(camera.save_jpeg, image, self.images_dir, self.instance)
        self.last_image = relative.as_posix()
        report = {"image": self.last_image, "width": image.width, "height": image.height, "topic": topic}
        return report, image

    async def detect_people(self, timeout: float) -> dict[str, Any]:
        """Take a picture and find the people in it, placed by the pose it was taken at (in get_pose's frame)."""
        report, image = await self.capture_frame(timeout)
        try:  # on the map when the robot is localized on one, else on odometry
            framed = await self.navigator.pose()
            pose: tuple[float, float, float] | None = (framed.x, framed.y, framed.yaw)
            frame = {"frame": framed.frame, "anchor": framed.anchor}
        except DeviceError:  # no pose: bearing and distance only
            pose, frame = None, {}
        people = [
            person | frame if "x" in person else person for person in await self.sightings.detect(image, pose)
        ]
        where = (
            {"x": round(pose[0], 3), "y": round(pose[1], 3), "yaw": round(pose[2], 3)} | frame
            if pose
            else None
        )
        return {"found": bool(people), "count": len(people), "people": people, **report, "pose": where}

    # Motion

    async def drive(self, linear: float, angular: float, duration: float, wait: bool) -> MotionResult:
        """A timed drive (renewable), within the velocity limits."""
        self.limits.check(linear, angular)
        if duration > self.profile.max_drive_duration:
            raise Refused(
                f"refused: one drive lasts at most {self.profile.max_drive_duration:g} s (profile {self.profile.name} "
                "max_drive_duration), so a lost client cannot leave the robot moving; call drive again to go on, "
                "or use move_distance"
            )
        await self.check_may_move()
        return await self.motion.drive(linear, angular, duration, wait)

    async def move_distance(self, meters: float, speed: float | None) -> MotionResult:
        """Straight, closed loop on odometry."""
        speed = self._speed(speed, self.profile.speeds.linear, "linear")
        await self.check_may_move()
        return await self.motion.move_distance(meters, speed)

    async def rotate(self, degrees: float, speed: float | None) -> MotionResult:
        """In place, closed loop on odometry; positive degrees turn left (counter-clockwise)."""
        speed = self._speed(speed, self.profile.speeds.angular, "angular")
        await self.check_may_move()
        return await self.motion.rotate(math.radians(degrees), speed)

    async def get_pose(self) -> dict[str, Any]:
        """Where the robot is, with the frame and its anchor (what a saved place keeps)."""
        return (await self.navigator.pose()).as_dict()

    async def go_to(
        self,
        x: float,
        y: float,
        yaw: float | None,
        anchor: str | None,
        on_feedback: FeedbackCallback | None,
    ) -> dict[str, Any]:
        """Drive to a pose: Nav2 on the map when the profile has it, else on odometry (see navigation)."""
        return await self.navigator.go_to(x, y, yaw, anchor, on_feedback)

    async def search(
        self,
        max_seconds: float,
        max_distance: float,
        progress: Progress,
        alive: Callable[[], Awaitable[bool]],
    ) -> dict[str, Any]:
        """Look for a person: turn, take pictures, move to nearby spots (see :mod:`rosaos_ros.search`)."""
        if self.profile.odom is None or (self.profile.camera is None and self.settings.camera_topic is None):
            raise DeviceError(
                f"{self.instance}: search needs odometry and a camera, and the {self.profile.name} profile "
                "lacks one; use detect_people with drive or rotate instead"
            )
        if self.search_run is not None:
            raise Refused(f"refused: {self.instance} is already searching; stop it first")
        await self.check_may_move()
        await self.state.wait_for_messages(sources={"odom"})
        self.search_run = SearchRun(self, max_seconds, max_distance, progress, alive)
        try:
            return await self.search_run.run()
        finally:
            self.search_run = None

    async def stop(self) -> dict[str, Any]:
        """Stop moving now and cancel running goals."""
        return await self.safe_stop()

    def _speed(self, asked: float | None, default: float, kind: str) -> float:
        limit = self.limits.linear if kind == "linear" else self.limits.angular
        if asked is None:
            return min(default, limit)
        self.limits.check(asked if kind == "linear" else 0.0, asked if kind == "angular" else 0.0)
        return asked

    async def check_may_move(self) -> None:
        """Refuse motion while the profile's ``refuse_motion_while`` key holds (docked)."""
        key = self.profile.refuse_motion_while
        if not key:
            return
        await self.state.wait_for_messages(sources={key})  # right after start, the state may be unknown
        if self.state.fields.get(key) is True:
            fix = (
                "call undock first"
                if "undock" in self.profile.actions
                else f"wait until it is no longer {key}"
            )
            raise Refused(
                f"refused: {self.instance} is {key}, and the {self.profile.name} profile does not move while "
                f"{key} (refuse_motion_while); {fix}"
            )

    # Topics

    async def subscribe(self, topic: str, count: int, duration: float) -> dict[str, Any]:
        """Up to ``count`` messages from ``topic`` within ``duration`` s, summarised for the model."""
        msg_type = await self.rosapi.require_topic_type(topic)
        if normalize_type(msg_type) in (IMAGE, COMPRESSED_IMAGE):
            raise DeviceError(
                f"{topic} carries images; use capture_image (never put image bytes in the conversation)"
            )
        started = time.monotonic()
        messages = await self.bridge.collect(topic, msg_type, count=count, duration=duration)
        return {
            "topic": topic,
            "type": msg_type,
            "count": len(messages),
            "seconds": round(time.monotonic() - started, 2),
            "messages": [summarize(message) for message in messages],
        }

    async def publish(
        self, topic: str, msg: dict[str, Any], msg_type: str | None, duration: float, rate: float
    ) -> dict[str, Any]:
        """Publish ``msg`` once (``duration`` 0) or ``rate`` times a second for ``duration`` s."""
        velocity = topic == self.profile.cmd_vel.topic
        self.policy.check("publish", topic, VELOCITY_HINT if velocity else "")
        msg_type = msg_type or await self.rosapi.require_topic_type(topic)
        if velocity:  # a raw velocity message gets the limits, the docked rule and the deadman too
            self.limits.check(*twist_speeds(msg))
            await self.check_may_move()
            if not duration:  # one message, lasting RAW_TWIST_LIFETIME, then the zero twist
                duration, rate = RAW_TWIST_LIFETIME, 1 / RAW_TWIST_LIFETIME
            result = await self.motion.stream(
                "publish", lambda: self.bridge.publish(topic, msg_type, msg), duration, rate
            )
            return {"topic": topic, "type": msg_type, **result.as_dict()}
        started, sent = time.monotonic(), 0
        while True:
            self.bridge.publish(topic, msg_type, msg)
            sent += 1
            next_at = started + sent / rate
            if next_at >= started + duration:
                break
            await asyncio.sleep(max(0.0, next_at - time.monotonic()))
        return {
            "topic": topic,
            "type": msg_type,
            "published": sent,
            "seconds": round(time.monotonic() - started, 2),
        }

    # Services, parameters, actions

    async def call_service(self, service: str, request: dict[str, Any], timeout: float) -> dict[str, Any]:
        """Call an allowed service."""
        self.policy.check("services", service)
        response = await self.bridge.call_service(service, request, timeout)
        return {"service": service, "response": summarize(response)}

    async def set_param(self, name: str, value: Any) -> dict[str, Any]:
        """Set an allowed parameter and read it back."""
        self.policy.check("params", name)
        await self.rosapi.set_param(name, value)
        return {"name": name, "value": await self.rosapi.get_param(name)}

    async def delete_param(self, name: str) -> dict[str, Any]:
        """Delete an allowed parameter."""
        self.policy.check("params", name)
        await self.rosapi.delete_param(name)
        return {"name": name, "deleted": True}

    async def send_goal(
        self,
        action: str,
        goal: dict[str, Any],
        action_type: str | None,
        timeout: float,
        wait: bool,
        on_feedback: FeedbackCallback | None,
    ) -> dict[str, Any]:
        """Send a goal to an allowed action; with ``wait``, its feedback goes to ``on_feedback``."""
        self.policy.check("actions", action)
        action_type = action_type or await self.rosapi.action_type(action) or self._named_action_type(action)
        if not action_type:
            raise DeviceError(
                f"{self.instance}: cannot tell the type of action {action}; give action_type "
                "(e.g. nav2_msgs/action/NavigateToPose); list_actions shows the actions"
            )
        record = await self.goals.send(
            action, action_type, goal, timeout=timeout, wait=wait, on_feedback=on_feedback
        )
        return record.as_dict()

    async def run_named_action(self, name: str, on_feedback: FeedbackCallback | None) -> dict[str, Any]:
        """Run one of the profile's named actions (``dock``, ``undock``) and return the state after it."""
        action = self.profile.actions[name]
        await self.motion.stop(f"replaced by {name}")
        goal = await self.send_goal(
            action.action, dict(action.goal), action.type, action.timeout, True, on_feedback
        )
        if goal.get("status") == "succeeded" and action.leaves:
            await self.state.wait_for_fields(action.leaves, STATE_SETTLE_WAIT)
        else:
            await self.state.refresh()
        return {"goal": goal, "state": await self.get_state()}

    def _named_action_type(self, action: str) -> str:
        return next((named.type for named in self.profile.actions.values() if named.action == action), "")
