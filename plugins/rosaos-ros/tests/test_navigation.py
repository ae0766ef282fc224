"""go_to over the socket: Nav2's NavigateToPose on the simulator, around a pillar, and its refusals."""

from __future__ import annotations

import asyncio
import math
from typing import Any

import pytest

from rosaos_ros.sim.navigation import Obstacles

pytestmark = pytest.mark.slow


async def test_go_to_on_the_map_arrives_around_the_red_pillar(open_robot: Any) -> None:
    async with open_robot() as robot:
        trail: list[tuple[float, float]] = []
        world = robot.world
        original = world.step

        def step(dt: float, now: float) -> None:
            original(dt, now)
            trail.append((world.x, world.y))

        world.step = step  # type: ignore[method-assign]
        result = await robot.call("go_to", x=3.5, y=0.0, yaw=0.0)
    assert result["arrived"] is True
    assert math.hypot(world.x - 3.5, world.y) < 0.2
    assert result["pose"]["frame"] == "map"
    assert result["navigation"]["status"] == "succeeded"
    nearest = min(math.hypot(x - 2.0, y) for x, y in trail)
    assert nearest > 0.2, f"the robot passed {nearest:.2f} m from the pillar's centre: through it"


async def test_go_to_streams_distance_remaining_as_feedback(open_robot: Any) -> None:
    async with open_robot() as robot:
        result = await robot.call("go_to", x=1.0, y=0.5)
    assert result["navigation"]["feedback_count"] >= 1
    assert "distance_remaining" in result["navigation"]["last_feedback"]


async def test_a_goal_inside_a_pillar_fails_cleanly_and_the_robot_stays(open_robot: Any) -> None:
    async with open_robot() as robot:
        error = await robot.error("go_to", x=2.0, y=0.0)
        assert (robot.world.x, robot.world.y) == (pytest.approx(0.0, abs=0.01), pytest.approx(0.0, abs=0.01))
    assert "inside an obstacle" in error


async def test_get_pose_names_the_map_and_a_changed_odometry_origin_leaves_the_map_pose(
    open_robot: Any,
) -> None:
    async with open_robot(sim={"x": 1.0, "y": 0.5, "odom_origin": {"x": 1.0, "y": 0.5}}) as robot:
        pose = await robot.call("get_pose")
        state = await robot.call("get_state")
    assert (pose["x"], pose["y"]) == (pytest.approx(1.0, abs=0.01), pytest.approx(0.5, abs=0.01))
    assert pose["anchor"] == "map:/home/ubuntu/maps/sim_pillars.yaml"
    assert (state["x"], state["y"]) == (pytest.approx(0.0, abs=0.01), pytest.approx(0.0, abs=0.01))


async def test_a_goal_saved_on_another_map_is_refused_with_the_reason(open_robot: Any) -> None:
    async with open_robot() as robot:
        error = await robot.error("go_to", x=1.0, y=0.0, frame_anchor="map:/maps/office.yaml")
        assert all((lin, ang) == (0.0, 0.0) for _, lin, ang in robot.world.commands)
    assert "saved on another map (map:/maps/office.yaml)" in error


async def test_without_nav2_go_to_drives_on_odometry_and_refuses_an_earlier_session(open_robot: Any) -> None:
    async with open_robot(profile="generic", sim={}) as robot:
        pose = await robot.call("get_pose")
        result = await robot.call("go_to", x=0.5, y=0.5, yaw=0.0, frame_anchor=pose["anchor"])
        assert math.hypot(robot.world.x - 0.5, robot.world.y - 0.5) < 0.05
        error = await robot.error("go_to", x=0.0, y=0.0, frame_anchor="odom:turtlebot:0123456789ab")
    assert pose["frame"] == "odom"
    assert result["pose"]["frame"] == "odom"
    assert "saved on odometry in an earlier session" in error


async def test_stop_cancels_a_running_go_to(open_robot: Any, eventually: Any) -> None:
    async with open_robot() as robot:
        going = asyncio.ensure_future(robot.call("go_to", x=-1.0, y=1.0))
        await eventually(lambda: robot.world.autopilot is not None, what="a navigation start")
        await robot.call("stop")
        with pytest.raises(Exception, match="did not reach"):
            await going
        assert robot.world.autopilot is None
    assert Obstacles().blocked((robot.world.x, robot.world.y)) is None
