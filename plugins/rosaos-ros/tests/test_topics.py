"""Topic tools over the socket: list, inspect, read, publish, and the publish allow-list."""

from __future__ import annotations

from typing import Any

import pytest


async def test_list_topics_shows_names_and_types(open_robot: Any) -> None:
    async with open_robot() as robot:
        topics = {t["name"]: t["type"] for t in (await robot.call("list_topics"))["topics"]}
    assert topics["/odom"] == "nav_msgs/msg/Odometry"
    assert topics["/cmd_vel"] == "geometry_msgs/msg/Twist"


async def test_topic_info_counts_publishers_and_subscribers(open_robot: Any) -> None:
    async with open_robot() as robot:
        info = await robot.call("topic_info", topic="/odom")
    assert info["type"] == "nav_msgs/msg/Odometry"
    assert info["publisher_count"] == 1 and "/motion_control" in info["publishers"]
    assert "/rosbridge_websocket" in info["subscribers"]  # the driver's own odometry subscription


async def test_subscribe_once_reads_one_message(open_robot: Any) -> None:
    async with open_robot(sim={"x": 1.5}) as robot:
        result = await robot.call("subscribe_once", topic="/odom", timeout=2)
    assert result["message"]["pose"]["pose"]["position"]["x"] == pytest.approx(1.5)
    assert result["message"]["pose"]["covariance"][-1] == "... (36 items in all)"  # long arrays are cut


async def test_subscribe_for_collects_at_most_max_messages(open_robot: Any) -> None:
    async with open_robot() as robot:
        result = await robot.call("subscribe_for", topic="/dock_status", duration=3, max_messages=3)
    assert result["count"] == 3 and result["seconds"] < 2
    assert all("is_docked" in message for message in result["messages"])


async def test_subscribe_refuses_image_topics(open_robot: Any) -> None:
    async with open_robot() as robot:
        error = await robot.error("subscribe_once", topic="/oakd/rgb/preview/image_raw")
    assert "capture_image" in error


async def test_an_unknown_topic_is_named_in_the_error(open_robot: Any) -> None:
    async with open_robot() as robot:
        error = await robot.error("subscribe_once", topic="/nowhere", timeout=1)
    assert "no topic /nowhere" in error


async def test_publish_on_an_allowed_topic_reaches_the_robot(open_robot: Any, eventually: Any) -> None:
    ring = {"leds": [{"red": 0, "green": 0, "blue": 255}] * 6, "override_system": True}
    async with open_robot() as robot:
        result = await robot.call("publish", topic="/cmd_lightring", msg=ring)
        await eventually(
            lambda: "/cmd_lightring" in robot.world.extra_messages, what="the light ring message"
        )
        received = robot.world.extra_messages["/cmd_lightring"]
    assert result["published"] == 1 and result["type"] == "irobot_create_msgs/msg/LightringLeds"
    assert received == ring


async def test_publish_for_repeats_at_the_rate(open_robot: Any) -> None:
    async with open_robot() as robot:
        result = await robot.call("publish_for", topic="/cmd_audio", msg={"notes": []}, duration=0.5, rate=10)
    assert 4 <= result["published"] <= 6


async def test_a_topic_outside_the_allow_list_is_refused_with_how_to_allow_it(open_robot: Any) -> None:
    async with open_robot() as robot:
        error = await robot.error("publish", topic="/robot_power", msg={}, msg_type="std_msgs/msg/Empty")
    assert "not in the allow-list" in error
    assert 'publish_allow = ["/robot_power"]' in error and "[devices.turtlebot]" in error


async def test_a_deny_listed_topic_is_refused_even_when_allowed_by_a_glob(open_robot: Any) -> None:
    async with open_robot(publish_allow=["/cmd_*"], publish_deny=["/cmd_audio"]) as robot:
        error = await robot.error("publish", topic="/cmd_audio", msg={"notes": []})
        await robot.call("publish", topic="/cmd_lightring", msg={"leds": []})
    assert "denied by the rule '/cmd_audio' ([devices.turtlebot] publish_deny)" in error


async def test_raw_velocity_is_refused_by_default_and_points_to_the_motion_tools(open_robot: Any) -> None:
    async with open_robot() as robot:
        error = await robot.error("publish", topic="/cmd_vel", msg={"linear": {"x": 0.1}})
    assert "use drive, move_distance or rotate" in error


async def test_allowed_raw_velocity_keeps_the_limits_and_ends_in_a_zero_twist(
    open_robot: Any, eventually: Any
) -> None:
    fast = {"linear": {"x": 0.0, "y": 0.5, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
    slow = {"linear": {"x": 0.1, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
    async with open_robot(publish_allow=["/cmd_vel"]) as robot:
        error = await robot.error("publish", topic="/cmd_vel", msg=fast)
        result = await robot.call("publish", topic="/cmd_vel", msg=slow)
        await eventually(lambda: robot.world.commands[-1][1:] == (0.0, 0.0), what="the closing zero twist")
        moved = [linear for _, linear, _ in robot.world.commands if linear]
    assert "0.5 m/s is above the velocity limit" in error  # sideways counts too
    assert result["outcome"] == "done" and moved == [0.1]
