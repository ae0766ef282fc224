"""The deadman: a drive that is not renewed ends in a zero twist within its duration + 200 ms,
even when the MCP client dies mid-call or the device server's event loop stalls; and a velocity
stream that pauses mid-drive is followed by a zero twist within the heartbeat, as twist_mux does."""

from __future__ import annotations

import asyncio
import sys
import time
from pathlib import Path
from typing import Any

from rosaos.devices.serve import serve_http
from rosaos.drivers import DeviceContext
from rosaos_ros.deadman import MARGIN
from rosaos_ros.motion import HEARTBEAT
from rosaos_ros.plugin import sim_backend
from rosaos_ros.server import build_server
from rosaos_ros.settings import RosSettings

BOUND = 0.2
"""What the issue promises past the drive's duration."""

# A bare MCP client over streamable HTTP (httpx only: it starts fast): initialize, then call
# drive and block reading its answer until the test kills the process.
CLIENT = """
import json, sys
import httpx

url, token, duration = sys.argv[1], sys.argv[2], float(sys.argv[3])
headers = {"Authorization": f"Bearer {token}", "Accept": "application/json, text/event-stream"}
with httpx.Client(timeout=30) as http:
    init = {"jsonrpc": "2.0", "id": 1, "method": "initialize", "params": {
        "protocolVersion": "2025-06-18", "capabilities": {}, "clientInfo": {"name": "doomed", "version": "0"}}}
    answer = http.post(url, json=init, headers=headers)
    answer.raise_for_status()
    session = answer.headers.get("mcp-session-id")
    if session:
        headers["mcp-session-id"] = session
    http.post(url, json={"jsonrpc": "2.0", "method": "notifications/initialized"}, headers=headers)
    call = {"jsonrpc": "2.0", "id": 2, "method": "tools/call",
            "params": {"name": "drive", "arguments": {"linear": 0.2, "duration": duration}}}
    with http.stream("POST", url, json=call, headers=headers) as stream:
        print("calling", flush=True)
        for _ in stream.iter_lines():
            pass
"""


def start_and_stop(commands: list[tuple[float, float, float]]) -> tuple[float, float]:
    """When the robot was first told to move, and when it was next told to stop (monotonic s)."""
    first_move = next(t for t, linear, angular in commands if linear or angular)
    stop = next(t for t, linear, angular in commands if t > first_move and not linear and not angular)
    return first_move, stop


async def test_a_drive_stops_in_time_when_the_mcp_client_is_killed_mid_call(
    tmp_path: Path, eventually: Any
) -> None:
    duration = 1.5
    ctx = DeviceContext("turtlebot", "TurtleBot", RosSettings(profile="turtlebot4"), "sim", {}, tmp_path)
    backend = sim_backend(ctx)
    await backend.start()
    try:
        world = backend.simulator.simulator.world  # type: ignore[union-attr]
        async with serve_http(build_server(ctx, backend), "token") as served:
            client = await asyncio.create_subprocess_exec(
                sys.executable,
                "-c",
                CLIENT,
                served.url,
                "token",
                str(duration),
                stdout=asyncio.subprocess.PIPE,
            )
            try:
                await eventually(lambda: world.linear > 0, timeout=30, what="the client's drive starting")
            finally:
                client.kill()  # SIGKILL: no goodbye to the server
                await client.wait()
            await eventually(lambda: world.linear == 0.0, timeout=duration + 2, what="the robot stopping")
        first_move, stop = start_and_stop(list(world.commands))
    finally:
        await backend.close()
    assert stop - first_move <= duration + BOUND
    assert world.stopped_by == "zero twist"  # the driver stopped it, not the base's own timeout


async def test_the_watchdog_stops_the_robot_when_the_event_loop_stalls(
    open_robot: Any, eventually: Any
) -> None:
    duration = 0.6
    async with open_robot() as robot:
        await robot.call("get_state")  # the first state read waits for every state topic once
        await robot.call("drive", linear=0.2, duration=duration, wait=False)
        await eventually(lambda: robot.world.linear > 0, what="the drive starting")
        time.sleep(1.2)  # noqa: ASYNC251 - the point: the server's loop is stuck, the motion loop cannot run
        first_move, stop = start_and_stop(list(robot.world.commands))
        fired = robot.backend.deadman.fired
    assert fired == 1
    assert stop - first_move <= duration + BOUND


async def test_a_stalled_velocity_stream_stops_the_robot_long_before_the_drive_ends(
    open_robot: Any, eventually: Any
) -> None:
    # As twist_mux treats a silent input: the stream pausing is enough, the drive's deadline is not awaited.
    duration, stall = 5.0, 1.5
    async with open_robot() as robot:
        await robot.call("get_state")
        await robot.call("drive", linear=0.2, duration=duration, wait=False)
        await eventually(lambda: robot.world.linear > 0, what="the drive starting")
        stalled_at = time.monotonic()
        time.sleep(stall)  # noqa: ASYNC251 - the point: the server's loop is stuck mid-drive
        commands = list(robot.world.commands)
        await robot.call("stop")
    sent_before = [t for t, linear, _ in commands if t <= stalled_at and linear]
    zero_after = [t for t, linear, angular in commands if t > stalled_at and not linear and not angular]
    assert sent_before and zero_after, commands
    gap = zero_after[0] - sent_before[-1]
    assert gap <= HEARTBEAT + MARGIN + BOUND, f"the robot kept its velocity {gap:.2f} s into the stall"
