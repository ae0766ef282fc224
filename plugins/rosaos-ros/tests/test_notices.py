"""The ROS driver's device notices: docked/undocked, battery low, a person seen during a search."""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

from fastmcp import Client

from rosaos.drivers import DeviceContext, NoticeBoard
from rosaos_ros.plugin import SPEC, sim_backend
from rosaos_ros.server import build_server
from rosaos_ros.settings import RosSettings


@contextlib.asynccontextmanager
async def robot_with_notices(
    tmp_path: Path, sim: dict[str, Any]
) -> AsyncIterator[tuple[Client[Any], Any, NoticeBoard]]:
    """A TurtleBot on the simulator whose notices are validated against the driver's declarations."""
    board = NoticeBoard("turtlebot", "ros", SPEC.notices)
    ctx = DeviceContext(
        "turtlebot", "TurtleBot", RosSettings(profile="turtlebot4"), "sim", sim, tmp_path, notices=board
    )
    backend = sim_backend(ctx)
    await backend.start()
    try:
        async with Client(build_server(ctx, backend)) as client:
            yield client, backend, board
    finally:
        await backend.close()


def names(board: NoticeBoard) -> list[str]:
    return [notice.name for notice in board.after(0).notices]


async def test_undock_and_dock_are_notices_but_the_first_reading_is_not(
    tmp_path: Path, eventually: Any
) -> None:
    async with robot_with_notices(tmp_path, {"docked": True}) as (client, _, board):
        await client.call_tool("get_state", {})
        assert names(board) == []  # docked at start-up: nothing happened
        await client.call_tool("undock", {})
        await eventually(lambda: names(board) == ["undocked"], what="the undocked notice")
        await client.call_tool("dock", {})
        await eventually(lambda: names(board) == ["undocked", "docked"], what="the docked notice")
    assert board.after(0).notices[0].message == "turtlebot left its dock"


async def test_a_low_battery_is_said_once_until_it_recovers(tmp_path: Path, eventually: Any) -> None:
    async with robot_with_notices(tmp_path, {"battery": 0.3}) as (client, backend, board):
        world = backend.simulator.simulator.world
        await client.call_tool("get_state", {})
        world.battery = 0.19
        await eventually(lambda: names(board) == ["battery_low"], what="the battery_low notice")
        world.battery = 0.18
        await client.call_tool("get_state", {})
        world.battery = 0.5
        await eventually(lambda: backend.state.fields.get("battery") == 0.5, what="the recharge")
        world.battery = 0.1
        await eventually(lambda: names(board) == ["battery_low", "battery_low"], what="the second notice")
    first = board.after(0).notices[0]
    assert first.importance == "notify" and first.data == {"battery": 0.19}
    assert first.message == "turtlebot's battery is at 19%"


async def test_a_search_that_finds_someone_posts_person_seen(tmp_path: Path) -> None:
    async with robot_with_notices(tmp_path, {"people": [{"x": -2.5, "y": 0.5}]}) as (client, _, board):
        result = (await client.call_tool("search", {"max_seconds": 60})).structured_content
    [notice] = board.after(0).notices
    assert result["found"] is True and notice.name == "person_seen"
    assert notice.data == {"x": result["x"], "y": result["y"], "distance_m": result["distance_m"]}
    assert notice.message.startswith("turtlebot found a person")
