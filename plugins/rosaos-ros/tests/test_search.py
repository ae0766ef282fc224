"""search: a bounded long task that turns, looks and moves until it finds a person, with progress."""

from __future__ import annotations

import asyncio
import math
import sys
import time
from pathlib import Path
from typing import Any

import pytest

from rosaos.devices.serve import serve_http
from rosaos.drivers import DeviceContext
from rosaos_ros.plugin import sim_backend
from rosaos_ros.search import SearchRun
from rosaos_ros.server import build_server
from rosaos_ros.settings import RosSettings

DEMO_PERSON = {"x": -2.5, "y": 0.5}


@pytest.mark.slow  # the simulated robot drives the whole search in real time
async def test_search_finds_the_person_behind_the_robot_and_says_where(open_robot: Any) -> None:
    messages: list[str] = []

    async def on_progress(progress: float, total: float | None, message: str | None) -> None:
        messages.append(message or "")

    async with open_robot(sim={"docked": False, "people": [DEMO_PERSON]}) as robot:
        answer = await robot.client.call_tool("search", {}, progress_handler=on_progress)
        state = await robot.call("get_state")
    result = answer.structured_content
    assert result["found"] is True, result
    assert math.hypot(result["x"] - -2.5, result["y"] - 0.5) < 0.6
    assert result["travelled_m"] == 0  # seen from the start, by turning
    assert any("nobody yet" in message for message in messages), messages
    assert messages[-1] == "found a person"
    assert state["people_seen"][-1]["x"] == result["x"]


@pytest.mark.slow  # the simulated robot drives the whole search in real time
async def test_search_with_nobody_ends_in_time_within_its_distance_and_the_limits(open_robot: Any) -> None:
    async with open_robot(sim={"docked": False, "people": []}) as robot:
        started = time.monotonic()
        result = await robot.call("search", max_seconds=25, max_distance_m=1.0)
        took = time.monotonic() - started
        world = robot.world
        limits = robot.backend.limits
    assert result["found"] is False and "nobody found" in result["outcome"], result
    assert took < 25 + 8, "the last step may finish, nothing more"
    assert math.hypot(world.x, world.y) <= 1.1
    assert result["pictures"] >= 8
    assert result["travelled_m"] > 0.3, "nobody around the start: it moved to look from elsewhere"
    assert all(
        abs(linear) <= limits.linear and abs(angular) <= limits.angular
        for _, linear, angular in world.commands
    )
    assert world.linear == 0 and world.angular == 0


@pytest.mark.slow  # the simulated robot turns in real time until its limit
async def test_a_search_without_max_seconds_looks_as_long_as_the_robots_setting_says(
    open_robot: Any,
) -> None:
    totals: list[float | None] = []

    async def on_progress(progress: float, total: float | None, message: str | None) -> None:
        totals.append(total)

    async with open_robot(sim={"docked": False, "people": []}, search_seconds=5) as robot:
        answer = await robot.client.call_tool("search", {}, progress_handler=on_progress)
    result = answer.structured_content
    assert result["found"] is False and "nobody found" in result["outcome"], result
    assert totals and set(totals) == {5.0}, totals  # every report counts towards the setting's 5 s
    assert RosSettings().search_seconds == 120  # unset, a search looks for two minutes


def test_search_spots_are_rings_within_the_distance_limit() -> None:
    run = SearchRun(backend=None, max_seconds=60, max_distance=3.0, progress=None, alive=None)  # type: ignore[arg-type]
    run.start = (1.0, 2.0, 0.5)
    spots = run._waypoints()
    radii = sorted(round(math.hypot(x - 1.0, y - 2.0), 3) for x, y in spots)
    assert radii == [1.0] * 4 + [2.0] * 4
    assert SearchRun(None, 60, 0.0, None, None)._waypoints() == []  # type: ignore[arg-type]


async def test_search_is_refused_while_docked(open_robot: Any) -> None:
    async with open_robot(sim={"docked": True, "people": [DEMO_PERSON]}) as robot:
        error = await robot.error("search")
    assert "undock" in error


async def test_search_is_for_people_only(open_robot: Any) -> None:
    async with open_robot() as robot:
        error = await robot.error("search", target="cat")
    assert "people only" in error


async def test_the_emergency_stop_ends_a_search(open_robot: Any, eventually: Any) -> None:
    async with open_robot(sim={"docked": False, "people": []}) as robot:
        search = asyncio.create_task(robot.call("search", max_seconds=60))
        await eventually(lambda: robot.world.angular != 0, timeout=20, what="the search turning")
        await robot.backend.safe_stop()
        result = await asyncio.wait_for(search, 10)
        assert result["found"] is False and result["outcome"].startswith("stopped")
        assert robot.backend.search_run is None
        await asyncio.sleep(1.0)
        assert robot.world.angular == 0 and robot.world.linear == 0


SEARCHER = """
import sys, httpx
url, token = sys.argv[1], sys.argv[2]
headers = {"Authorization": f"Bearer {token}", "Accept": "application/json, text/event-stream"}
with httpx.Client(timeout=60) as http:
    init = {"jsonrpc": "2.0", "id": 1, "method": "initialize", "params": {
        "protocolVersion": "2025-06-18", "capabilities": {}, "clientInfo": {"name": "doomed", "version": "0"}}}
    answer = http.post(url, json=init, headers=headers)
    session = answer.headers.get("mcp-session-id")
    if session:
        headers["mcp-session-id"] = session
    http.post(url, json={"jsonrpc": "2.0", "method": "notifications/initialized"}, headers=headers)
    call = {"jsonrpc": "2.0", "id": 2, "method": "tools/call",
            "params": {"name": "search", "arguments": {"max_seconds": 120}, "_meta": {"progressToken": 7}}}
    with http.stream("POST", url, json=call, headers=headers) as stream:
        for _ in stream.iter_lines():
            pass
"""


@pytest.mark.slow  # a search in a worker subprocess, killed mid-way
async def test_a_search_stops_when_its_caller_is_killed(tmp_path: Path, eventually: Any) -> None:
    """terminate_process kills the worker: the search must not go on driving for its remaining minutes."""
    ctx = DeviceContext(
        "turtlebot", "TurtleBot", RosSettings(profile="turtlebot4"), "sim", {"people": []}, tmp_path
    )
    backend = sim_backend(ctx)
    await backend.start()
    try:
        world = backend.simulator.simulator.world  # type: ignore[union-attr]
        async with serve_http(build_server(ctx, backend), "token") as served:
            caller = await asyncio.create_subprocess_exec(sys.executable, "-c", SEARCHER, served.url, "token")
            try:
                await eventually(
                    lambda: backend.search_run is not None and world.angular != 0, timeout=30, what="search"
                )
            finally:
                caller.kill()
                await caller.wait()
            await eventually(lambda: backend.search_run is None, timeout=10, what="the search ending")
            await asyncio.sleep(1.0)
            assert world.linear == 0 and world.angular == 0
            moved = len(world.commands)
            await asyncio.sleep(2.0)
            assert all(not linear and not angular for _, linear, angular in list(world.commands)[moved:])
    finally:
        await backend.close()
