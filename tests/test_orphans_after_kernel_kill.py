"""A robot never moves without an owner: SIGKILL the kernel mid-motion, then restart it.

The robot is served by ``rosaos serve-device`` in its own process, as on a robot's own computer,
so it outlives the kernel. The kernel (``rosaos up``, offline engine) is told to walk the dog
three metres and is killed with SIGKILL while it walks. Then:

- the dog stops at once: its process's worker saw its kernel go and called ``safe_stop``;
- the restarted kernel reports the process as ``crashed (kernel restarted)`` with its task, and
  says the dog was safe-stopped, before its loop grants anything;
- the dog can be granted again and walks.
"""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from rosaos.devices.client import DeviceClient

from .cli_process import ROSAOS, line_matching


def start(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [str(ROSAOS), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**os.environ, "COLUMNS": "200"},
    )


@pytest.fixture
def robot(tmp_path: Path) -> Iterator[tuple[str, str]]:
    """The dog (a PuppyPi on the rosbridge simulator), served on its own; yields its URL and token."""
    config = tmp_path / "robot.toml"
    config.write_text(
        f'data_dir = "{tmp_path / "robot-data"}"\n'
        '[devices.dog]\ndriver = "ros"\nprofile = "puppypi"\n'
        'description = "Hiwonder PuppyPi robot dog"\n'
    )
    served = start("serve-device", "dog", "--config", str(config), "--port", "0")
    try:
        url = line_matching(served, r"(http://127\.0\.0\.1:\d+/mcp)").group(1)
        yield url, (tmp_path / "robot-data" / "token").read_text().strip()
    finally:
        served.send_signal(signal.SIGINT)
        try:
            served.wait(30)
        except subprocess.TimeoutExpired:
            served.kill()


def start_kernel(config: Path) -> tuple[subprocess.Popen[str], str]:
    kernel = start("up", "--config", str(config), "--port", "0")
    url = line_matching(kernel, r"rosaOS is up at (http://\S+?)/?$").group(1)
    return kernel, url


async def dog_x(url: str, token: str) -> float:
    async with DeviceClient(url, token, 10, "dog") as dog:
        return float((await dog.get_state())["x"])


def eventually(check: Any, timeout: float = 60.0) -> Any:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = check()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"condition not met within {timeout} s")


def test_a_kernel_killed_mid_motion_leaves_no_robot_moving_and_reports_the_orphan(
    robot: tuple[str, str], tmp_path: Path
) -> None:
    robot_url, robot_token = robot
    config = tmp_path / "rosaos.toml"
    config.write_text(
        f'data_dir = "{tmp_path / "data"}"\n[kernel]\npool_size = 1\n'
        f'[devices.dog]\ndriver = "ros"\nurl = "{robot_url}"\ntoken = "{robot_token}"\n'
        'description = "Hiwonder PuppyPi robot dog"\n'
    )
    kernel, url = start_kernel(config)
    token = (tmp_path / "data" / "token").read_text().strip()
    headers = {"Authorization": f"Bearer {token}"}
    try:
        with httpx.Client(base_url=url, headers=headers, timeout=10) as api:
            api.post("/chat", json={"text": "make the dog walk forward 3 meters"}).raise_for_status()
            # The banner does not wait for the warm pool: on a busy machine the first command
            # also waits for the fork server's imports.
            eventually(lambda: asyncio.run(dog_x(robot_url, robot_token)) > 0.2, timeout=180)
    finally:
        kernel.send_signal(signal.SIGKILL)
        kernel.wait()

    time.sleep(1.5)  # the worker sees its pipe close and stops the dog; the base settles
    settled = asyncio.run(dog_x(robot_url, robot_token))
    time.sleep(2.0)
    assert asyncio.run(dog_x(robot_url, robot_token)) == pytest.approx(settled, abs=0.02), (
        "the dog kept walking after its kernel was killed"
    )
    assert settled < 2.5, "the dog walked its whole way: nothing stopped it"

    kernel, url = start_kernel(config)
    try:
        with httpx.Client(base_url=url, headers=headers, timeout=10) as api:
            updates = api.get("/updates", params={"after": 0, "limit": 1000}).json()["updates"]
            ended = [u for u in updates if u["kind"] == "process_ended"]
            crashed = [u for u in ended if "crashed (kernel restarted" in u["text"]]
            assert len(crashed) == 1, ended
            assert crashed[0]["data"]["task"].lower().startswith("make the dog walk forward")
            assert "dog safe-stopped" in crashed[0]["data"]["error"]
            # The dog is free again: a new process gets it and walks.
            api.post("/chat", json={"text": "make the dog walk forward half a meter"}).raise_for_status()
            eventually(lambda: asyncio.run(dog_x(robot_url, robot_token)) > settled + 0.1, timeout=180)
    finally:
        kernel.send_signal(signal.SIGINT)
        kernel.wait(60)
