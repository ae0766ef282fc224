"""A profile brought to life in the simulated ROS graph: nodes, topics, services, actions, params.

The base node subscribes to the velocity topic and publishes odometry at 50 Hz; with the
profile's ``sim.battery``/``sim.dock`` it also publishes the ``battery``/``docked`` state topics
and serves the ``dock``/``undock`` actions (irobot_create_msgs shapes). Cameras render only while
a client subscribes to them, and show the world's people when they are in view.
"""

from __future__ import annotations

import asyncio
import time
from typing import Any

from rosaos_ros.messages import header, quaternion_from_yaw, twist_command, yaw_from_quaternion
from rosaos_ros.profiles import Profile
from rosaos_ros.sim.graph import ActionAborted, ActionGoal, ActionServer, Message, RosGraph, ServiceFailure
from rosaos_ros.sim.images import compressed_image_message, raw_image_message, render
from rosaos_ros.sim.navigation import PathPilot, PlanningError, path_length, plan_path
from rosaos_ros.sim.world import Autopilot, DiffDriveWorld, SimState

RATE_HZ = 50
STATE_EVERY = 5  # ticks: battery and dock status at 10 Hz
CAMERA_EVERY = 10  # ticks: cameras at 5 Hz (only while subscribed)
FEEDBACK_PERIOD = 0.2
DOCK_TIMEOUT = 60.0
BATTERY_STATE = "sensor_msgs/msg/BatteryState"
DOCK_STATUS = "irobot_create_msgs/msg/DockStatus"


class SimulatedRobot:
    """The simulated robot of one profile, registered in ``graph``."""

    def __init__(self, profile: Profile, state: SimState, graph: RosGraph) -> None:
        self.profile = profile
        self.graph = graph
        self.world = DiffDriveWorld.from_state(state, profile.sim.hardware_limits)
        self._ticks = 0
        self.odometry_stalled_until = 0.0
        """Monotonic time until which the base publishes no odometry: a stalled base driver, or a
        busy machine. Physics go on; a test sets it to see what a closed loop does while blind."""
        self._declare()

    def _declare(self) -> None:
        profile, sim, graph = self.profile, self.profile.sim, self.graph
        base = sim.base_node
        graph.add_node(base)
        for node, params in sim.params.items():
            graph.add_node(node, dict(params))
        graph.add_subscriber(profile.cmd_vel.topic, profile.cmd_vel.type, base, self._on_cmd_vel)
        if profile.odom is not None:
            graph.add_publisher(profile.odom.topic, profile.odom.type, base)
        for topic, msg_type in sim.topics.items():
            graph.add_subscriber(topic, msg_type, base, self._recorder(topic))
        if sim.battery and "battery" in profile.state:
            graph.add_publisher(profile.state["battery"].topic, BATTERY_STATE, base)
        if sim.dock and "docked" in profile.state:
            graph.add_publisher(profile.state["docked"].topic, DOCK_STATUS, base)
        if sim.cameras:
            graph.add_node(sim.camera_node)
        for topic, encoding in sim.cameras.items():
            kind = "sensor_msgs/msg/CompressedImage" if encoding == "jpeg" else "sensor_msgs/msg/Image"
            graph.add_publisher(topic, kind, sim.camera_node)
        prefix = base.rsplit("/", 1)[0]  # the namespace, if any
        if "e_stop" in sim.services:
            graph.add_service(f"{prefix}/e_stop", "irobot_create_msgs/srv/EStop", base, self._e_stop)
        if "reset_pose" in sim.services:
            graph.add_service(
                f"{prefix}/reset_pose", "irobot_create_msgs/srv/ResetPose", base, self._reset_pose
            )
        navigation = profile.navigation
        if navigation is not None:
            graph.add_publisher(navigation.pose.topic, navigation.pose.type, "/amcl")
            graph.add_action(
                navigation.action,
                ActionServer(navigation.type, "/bt_navigator", self._navigate, _navigation_result),
            )
        if sim.dock:
            result = self._dock_result
            if "dock" in profile.actions:
                action = profile.actions["dock"]
                graph.add_action(action.action, ActionServer(action.type, base, self._dock, result))
            if "undock" in profile.actions:
                action = profile.actions["undock"]
                graph.add_action(action.action, ActionServer(action.type, base, self._undock, result))

    async def run(self) -> None:
        """Step the world and publish at :data:`RATE_HZ` until cancelled."""
        period = 1 / RATE_HZ
        last = time.monotonic()
        while True:
            await asyncio.sleep(max(0.0, last + period - time.monotonic()))
            now = time.monotonic()
            self.tick(min(now - last, 0.1), now)
            last = now

    def tick(self, dt: float, now: float) -> None:
        """Advance the world by ``dt`` and publish what is due."""
        self.world.step(dt, now)
        self._ticks += 1
        if now >= self.odometry_stalled_until:
            self._publish_odometry()
        if self._ticks % STATE_EVERY == 0:
            self._publish_dock_status()
            self._publish_battery()
            self._publish_map_pose()
        if self._ticks % CAMERA_EVERY == 0:
            self._publish_cameras()

    # Topics

    def _on_cmd_vel(self, msg: Message) -> None:
        linear, angular = twist_command(msg)
        self.world.command(linear, angular, time.monotonic())

    def _recorder(self, topic: str) -> Any:
        def record(msg: Message) -> None:
            self.world.extra_messages[topic] = msg

        return record

    def _publish_odometry(self) -> None:
        odom, world = self.profile.odom, self.world
        if odom is None:
            return
        zero36 = [0.0] * 36
        x, y, yaw = world.odometry_pose()
        self.graph.publish(
            odom.topic,
            {
                "header": header("odom"),
                "child_frame_id": "base_link",
                "pose": {
                    "pose": {
                        "position": {"x": x, "y": y, "z": 0.0},
                        "orientation": quaternion_from_yaw(yaw),
                    },
                    "covariance": zero36,
                },
                "twist": {
                    "twist": {
                        "linear": {"x": world.linear, "y": 0.0, "z": 0.0},
                        "angular": {"x": 0.0, "y": 0.0, "z": world.angular},
                    },
                    "covariance": zero36,
                },
            },
        )

    def _publish_map_pose(self) -> None:
        """Where the robot is on the map (the world frame), as AMCL reports it."""
        navigation = self.profile.navigation
        if navigation is not None:
            msg = {
                "header": header(navigation.frame),
                "pose": {"pose": self._map_pose(), "covariance": [0.0] * 36},
            }
            self.graph.publish(navigation.pose.topic, msg)

    def _map_pose(self) -> Message:
        return {
            "position": {"x": self.world.x, "y": self.world.y, "z": 0.0},
            "orientation": quaternion_from_yaw(self.world.yaw),
        }

    def _publish_dock_status(self) -> None:
        field = self.profile.state.get("docked")
        if self.profile.sim.dock and field is not None:
            msg = {
                "header": header("base_link"),
                "dock_visible": self.world.dock_in_sight(),
                "is_docked": self.world.docked,
            }
            self.graph.publish(field.topic, msg)

    def _publish_battery(self) -> None:
        field = self.profile.state.get("battery")
        if not self.profile.sim.battery or field is None:
            return
        charging = self.world.docked and self.world.battery < 1.0
        self.graph.publish(
            field.topic,
            {
                "header": header("base_link"),
                "voltage": 14.0 + 2.0 * self.world.battery,
                "temperature": 25.0,
                "current": 1.2 if charging else -0.6,
                "charge": 2.6 * self.world.battery,
                "capacity": 2.6,
                "design_capacity": 2.6,
                "percentage": round(self.world.battery, 4),
                "power_supply_status": 1 if charging else 2,  # CHARGING / DISCHARGING
                "power_supply_health": 1,
                "power_supply_technology": 2,  # LION
                "present": True,
                "cell_voltage": [],
                "cell_temperature": [],
                "location": "",
                "serial_number": "",
            },
        )

    def _publish_cameras(self) -> None:
        wanted = [(t, e) for t, e in self.profile.sim.cameras.items() if self.graph.has_bridge_subscribers(t)]
        if not wanted:
            return
        image = render(self.world.x, self.world.y, self.world.yaw, self.world.people)
        for topic, encoding in wanted:
            make = compressed_image_message if encoding == "jpeg" else raw_image_message
            self.graph.publish(topic, make(image, "camera_link"))

    # Services

    async def _e_stop(self, request: Message) -> Message:
        self.world.e_stop = bool(request.get("e_stop_on", False))
        state = "on: the wheels will not move" if self.world.e_stop else "off"
        return {"success": True, "message": f"e-stop {state}"}

    async def _reset_pose(self, request: Message) -> Message:
        pose = request.get("pose") or {}
        if not isinstance(pose, dict):
            raise ServiceFailure("pose must be a geometry_msgs/Pose object")
        position = pose.get("position") or {}
        yaw = yaw_from_quaternion(pose.get("orientation") or {"w": 1.0})
        self.world.reset_pose(float(position.get("x", 0.0)), float(position.get("y", 0.0)), yaw)
        return {}

    # Actions

    async def _navigate(self, goal: ActionGoal) -> Message:
        """NavigateToPose: plan around the pillars, follow the plan, report the distance left."""
        navigation, world = self.profile.navigation, self.world
        assert navigation is not None
        stamped = goal.goal.get("pose") or {}
        frame = str((stamped.get("header") or {}).get("frame_id") or navigation.frame)
        if frame != navigation.frame:
            raise ActionAborted(
                _navigation_result(f"goals are in the {navigation.frame} frame, not {frame}", 1)
            )
        pose = stamped.get("pose") or {}
        position = pose.get("position") or {}
        target = (float(position.get("x", 0.0)), float(position.get("y", 0.0)))
        orientation = pose.get("orientation")
        yaw = yaw_from_quaternion(orientation) if orientation else None
        try:
            waypoints = plan_path((world.x, world.y), target)
        except PlanningError as error:
            raise ActionAborted(_navigation_result(str(error), 2)) from None
        speeds, limits = self.profile.speeds, world.hardware_limits
        pilot = PathPilot(
            waypoints, yaw, min(speeds.linear, limits.linear), min(speeds.angular, limits.angular)
        )
        timeout = path_length((world.x, world.y), waypoints) / pilot.speed * 3 + 30
        world.autopilot = pilot
        started = time.monotonic()
        try:
            while world.autopilot is pilot:
                elapsed = time.monotonic() - started
                if world.e_stop or elapsed > timeout:
                    reason = "the e-stop is on" if world.e_stop else f"not there after {timeout:.0f} s"
                    raise ActionAborted(_navigation_result(reason, 3))
                goal.feedback(
                    {
                        "current_pose": {"header": header(navigation.frame), "pose": self._map_pose()},
                        "navigation_time": {"sec": int(elapsed), "nanosec": 0},
                        "number_of_recoveries": 0,
                        "distance_remaining": round(pilot.remaining(world), 3),
                    }
                )
                await asyncio.sleep(FEEDBACK_PERIOD)
        finally:
            if world.autopilot is pilot:
                world.autopilot = None
        return _navigation_result("", 0)

    def _dock_result(self) -> Message:
        return {"is_docked": self.world.docked}

    async def _dock(self, goal: ActionGoal) -> Message:
        world = self.world
        if world.docked:
            return {"is_docked": True}
        limits = world.hardware_limits
        dock = world.dock
        world.autopilot = Autopilot(
            dock.x, dock.y, dock.yaw, min(0.3, limits.linear), min(2.0, limits.angular)
        )
        started = time.monotonic()
        try:
            while world.autopilot is not None:
                if world.e_stop or time.monotonic() - started > DOCK_TIMEOUT:
                    raise ActionAborted({"is_docked": False})
                goal.feedback({"sees_dock": world.dock_in_sight()})
                await asyncio.sleep(FEEDBACK_PERIOD)
        finally:
            world.autopilot = None
        if not world.on_dock_pose():
            raise ActionAborted({"is_docked": False})
        world.docked = True
        goal.feedback({"sees_dock": True})
        return {"is_docked": True}

    async def _undock(self, goal: ActionGoal) -> Message:
        # A real Create 3 backs off the dock and turns around; the simulated one is released in
        # place, so an undock changes nothing but `docked` (what the bench tasks expect).
        if not self.world.docked:
            return {"is_docked": False}
        for _ in range(3):  # about as long as a Create 3 takes to let go of its dock's contacts
            goal.feedback({})
            await asyncio.sleep(FEEDBACK_PERIOD / 2)
        self.world.docked = False
        return {"is_docked": False}


def _navigation_result(error: str = "", code: int = 0) -> Message:
    """NavigateToPose's result (Jazzy's fields; Humble's is empty): an error code and message."""
    return {"error_code": code, "error_msg": error}
