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
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from rosaos.devices.client import DeviceClient

from .e2e_support import DOG, remote_device, served_device, start_kernel


@pytest.fixture
def robot(tmp_path: Path) -> Iterator[tuple[str, str]]:
    """The dog (a PuppyPi on the rosbridge simulator), served on its own; yields its URL and token."""
    with served_device(tmp_path, "dog", DOG) as served:
        yield served


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
        + remote_device("dog", robot_url, robot_token, "Hiwonder PuppyPi robot dog")
    )
    kernel = start_kernel(config)  # ready: the dog is up and the workers are warm
    try:
        with kernel.api() as api:
            api.post("/chat", json={"text": "make the dog walk forward 3 meters"}).raise_for_status()
            eventually(lambda: asyncio.run(dog_x(robot_url, robot_token)) > 0.2, timeout=30)
    finally:
        kernel.kill()

    time.sleep(1.5)  # the worker sees its pipe close and stops the dog; the base settles
    settled = asyncio.run(dog_x(robot_url, robot_token))
    time.sleep(2.0)
    assert asyncio.run(dog_x(robot_url, robot_token)) == pytest.approx(settled, abs=0.02), (
        "the dog kept walking after its kernel was killed"
    )
    assert settled < 2.5, "the dog walked its whole way: nothing stopped it"

    kernel = start_kernel(config)
    try:
        with kernel.api() as api:
            updates = api.get("/updates", params={"after": 0, "limit": 1000}).json()["updates"]
            ended = [u for u in updates if u["kind"] == "process_ended"]
            crashed = [u for u in ended if "crashed (kernel restarted" in u["text"]]
            assert len(crashed) == 1, ended
            assert crashed[0]["data"]["task"].lower().startswith("make the dog walk forward")
            assert "dog safe-stopped" in crashed[0]["data"]["error"]
            # The dog is free again: a new process gets it and walks.
            api.post("/chat", json={"text": "make the dog walk forward half a meter"}).raise_for_status()
            eventually(lambda: asyncio.run(dog_x(robot_url, robot_token)) > settled + 0.1, timeout=30)
    finally:
        kernel.stop()
