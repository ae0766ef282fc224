"""A Nav2 goal ends when its owner dies: the device host's deadman cancels it, not only the twist.

The turtlebot is served by ``rosaos serve-device`` on its own, on the rosbridge simulator with its
Nav2 ``NavigateToPose`` action. A bare MCP client in a subprocess names itself as the owner (as a
worker does), calls ``go_to`` on the far side of the map and is killed with SIGKILL mid-goal,
sending no keepalive ever again. Within the deadman's 1.5 s of silence plus the issue's 2 s bound,
the goal must be cancelled and the robot still; it must not drive on to the goal on its own.
"""

from __future__ import annotations

import asyncio
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from rosaos.devices.client import DeviceClient
from rosaos.devices.deadman import OWNER_HEADER, SILENCE_LIMIT

from .cli_process import line_matching
from .test_orphans_after_kernel_kill import start

STOP_BOUND = 2.0
"""Seconds past the deadman's silence limit by which the robot must be still (issue 21's bound)."""

# A bare MCP client (httpx only): initialize as owner "worker-doomed", call go_to, and block on its
# answer until the test kills the process.
CLIENT = f"""
import sys
import httpx

url, token = sys.argv[1], sys.argv[2]
headers = {{"Authorization": f"Bearer {{token}}", "Accept": "application/json, text/event-stream",
           "{OWNER_HEADER}": "worker-doomed"}}
with httpx.Client(timeout=120) as http:
    init = {{"jsonrpc": "2.0", "id": 1, "method": "initialize", "params": {{
        "protocolVersion": "2025-06-18", "capabilities": {{}}, "clientInfo": {{"name": "doomed", "version": "0"}}}}}}
    answer = http.post(url, json=init, headers=headers)
    answer.raise_for_status()
    session = answer.headers.get("mcp-session-id")
    if session:
        headers["mcp-session-id"] = session
    http.post(url, json={{"jsonrpc": "2.0", "method": "notifications/initialized"}}, headers=headers)
    call = {{"jsonrpc": "2.0", "id": 2, "method": "tools/call",
            "params": {{"name": "go_to", "arguments": {{"x": -2.0, "y": 2.0}}}}}}
    with http.stream("POST", url, json=call, headers=headers) as stream:
        print("calling", flush=True)
        for _ in stream.iter_lines():
            pass
"""


@pytest.fixture
def turtlebot(tmp_path: Path) -> Iterator[tuple[str, str]]:
    """The turtlebot (undocked, with Nav2) on the rosbridge simulator, served on its own."""
    config = tmp_path / "robot.toml"
    config.write_text(
        f'data_dir = "{tmp_path / "robot-data"}"\n'
        '[devices.turtlebot]\ndriver = "ros"\nprofile = "turtlebot4"\nsim = { docked = false }\n'
        'description = "TurtleBot4 with Nav2"\n'
    )
    served = start("serve-device", "turtlebot", "--config", str(config), "--port", "0")
    try:
        url = line_matching(served, r"(http://127\.0\.0\.1:\d+/mcp)").group(1)
        yield url, (tmp_path / "robot-data" / "token").read_text().strip()
    finally:
        served.send_signal(signal.SIGINT)
        try:
            served.wait(30)
        except subprocess.TimeoutExpired:
            served.kill()


def state(url: str, token: str) -> dict[str, Any]:
    async def read() -> dict[str, Any]:
        async with DeviceClient(url, token, 10, "turtlebot") as client:
            return await client.get_state()

    return asyncio.run(read())


def wait_for(check: Any, timeout: float, what: str) -> float:
    started = time.monotonic()
    while time.monotonic() - started < timeout:
        if check():
            return time.monotonic() - started
        time.sleep(0.05)
    raise AssertionError(f"{what}: not within {timeout} s")


def moving(now: dict[str, Any]) -> bool:
    return abs(now["linear"]) > 0.001 or abs(now["angular"]) > 0.001


def test_a_navigation_goal_is_cancelled_when_its_owner_dies(turtlebot: tuple[str, str]) -> None:
    url, token = turtlebot
    client = subprocess.Popen([sys.executable, "-c", CLIENT, url, token], stdout=subprocess.PIPE, text=True)
    try:
        wait_for(lambda: moving(state(url, token)), 60, "the goal under way")
    finally:
        client.kill()  # SIGKILL: no release, no keepalive, no goodbye
        client.wait()
    killed = time.monotonic()
    wait_for(lambda: not moving(state(url, token)), SILENCE_LIMIT + STOP_BOUND + 5, "the robot stopping")
    stopped_after = time.monotonic() - killed
    held = state(url, token)
    time.sleep(2.0)  # a goal still running on the navigation server would move the robot again
    later = state(url, token)
    print(f"the robot was still {stopped_after:.2f} s after its owner died")
    assert stopped_after < SILENCE_LIMIT + STOP_BOUND, f"still moving {stopped_after:.1f} s after"
    assert not moving(later), "the navigation goal drove on after its owner died"
    assert abs(later["x"] - held["x"]) < 0.02 and abs(later["y"] - held["y"]) < 0.02
