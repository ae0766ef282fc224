"""Actions over the socket: goals with feedback as MCP progress, cancel, status, the named actions."""

from __future__ import annotations

import asyncio
from typing import Any


async def test_list_actions_shows_the_dock_and_navigation_actions(open_robot: Any) -> None:
    async with open_robot() as robot:
        actions = {a["name"]: a["type"] for a in (await robot.call("list_actions"))["actions"]}
    assert actions == {
        "/dock": "irobot_create_msgs/action/Dock",
        "/undock": "irobot_create_msgs/action/Undock",
        "/navigate_to_pose": "nav2_msgs/action/NavigateToPose",
    }


async def test_dock_streams_feedback_as_progress_and_ends_docked(open_robot: Any) -> None:
    progress: list[tuple[float, str | None]] = []

    async def on_progress(value: float, total: float | None, message: str | None) -> None:
        progress.append((value, message))

    async with open_robot(sim={"x": 0.2}) as robot:
        result = await robot.client.call_tool("dock", {}, progress_handler=on_progress)
    report = result.structured_content
    assert report["goal"]["status"] == "succeeded" and report["goal"]["result"] == {"is_docked": True}
    assert report["state"]["docked"] is True and abs(report["state"]["x"]) < 0.03
    assert len(progress) >= 2 and progress[0] == (1.0, '{"sees_dock": true}')
    assert report["goal"]["feedback_count"] >= len(progress)


async def test_a_goal_can_be_cancelled_and_its_status_read(open_robot: Any) -> None:
    async with open_robot(sim={"x": 1.0}) as robot:
        sent = await robot.call("send_goal", action="/dock", goal={}, wait=False)
        await asyncio.sleep(0.4)
        running = await robot.call("goal_status", goal_id=sent["goal_id"])
        cancelled = await robot.call("cancel_goal", goal_id=sent["goal_id"])
        every = await robot.call("goal_status")
    assert sent["status"] == "running" and running["feedback_count"] >= 1
    assert cancelled["status"] == "canceled" and cancelled["result"] == {"is_docked": False}
    assert [goal["goal_id"] for goal in every["goals"]] == [sent["goal_id"]]
    assert robot.world.autopilot is None


async def test_send_goal_cancels_a_goal_that_outlasts_its_timeout(open_robot: Any) -> None:
    async with open_robot(sim={"x": 1.0}) as robot:
        result = await robot.call("send_goal", action="/dock", goal={}, timeout=0.5)
    assert result["status"] == "canceled" and "cancelled" in result["error"]


async def test_stop_cancels_running_goals(open_robot: Any) -> None:
    async with open_robot(sim={"x": 1.0}) as robot:
        sent = await robot.call("send_goal", action="/dock", goal={}, wait=False)
        await asyncio.sleep(0.3)
        stopped = await robot.call("stop")
        await asyncio.sleep(0.2)
        status = await robot.call("goal_status", goal_id=sent["goal_id"])
    assert stopped["cancelled_goals"] == [sent["goal_id"]]
    assert status["status"] == "canceled"


async def test_an_action_outside_the_allow_list_is_refused(open_robot: Any) -> None:
    async with open_robot(action_deny=["/dock"]) as robot:
        error = await robot.error("dock")
        other = await robot.error("send_goal", action="/drive_distance", goal={"distance": 1.0})
    assert "denied by the rule '/dock' ([devices.turtlebot] action_deny)" in error
    assert "action_allow" in other


async def test_undock_is_a_tool_and_a_puppypi_has_no_dock_tool(open_robot: Any) -> None:
    async with open_robot(sim={"docked": True}) as robot:
        result = await robot.call("undock")
    async with open_robot(instance="dog", profile="puppypi", sim={}) as dog:
        tools = {tool.name for tool in await dog.client.list_tools()}
    assert result["state"]["docked"] is False and result["goal"]["status"] == "succeeded"
    assert "dock" not in tools and "undock" not in tools and "move_distance" in tools
