"""A person's "stop" stops a moving robot whoever holds it, and questions are answered while it is held.

The real kernel with the offline engine, its API on loopback, worker subprocesses, and the ROS
and Spotify simulators over MCP HTTP. "Stopped within 0.5 s of handling" is checked as: once
the stop's event is handled, the robot's pose no longer changes over the next 0.5 s (the stop
ran inside the handling, so the robot was already stopped when it was marked handled).
"""

from __future__ import annotations

import asyncio
import subprocess
from collections.abc import AsyncIterator, Awaitable, Callable
from pathlib import Path
from typing import Any

import httpx
import pytest
import pytest_asyncio

from rosaos.kernel.runtime import Kernel
from rosaos.processes.queue_behind import QUEUE_WAIT

from .cli_process import ROSAOS
from .e2e_support import (
    all_healthy,
    chat,
    device_state,
    eventually,
    handled,
    kernel_api,
    running_kernel,
    updates_of,
)

pytestmark = pytest.mark.asyncio(loop_scope="module")
WalkingDog = Callable[[str], Awaitable[dict[str, Any]]]

WORLD = """
[devices.turtlebot]
driver = "ros"
description = "TurtleBot4 wheeled mobile robot with a camera and a charging dock"
profile = "turtlebot4"
sim = { docked = false }

[devices.dog]
driver = "ros"
description = "Hiwonder PuppyPi quadruped robot dog"
profile = "puppypi"

[devices.spotify]
driver = "spotify"
description = "Music on the lab speaker"
sim = { is_playing = false, catalog = [{ track = "Here Comes the Sun", artist = "The Beatles", album = "Abbey Road", genre = "rock" }] }
"""

STILL = 0.02
"""Metres the pose may drift in 0.5 s and still count as stopped (odometry noise, one last tick)."""


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def home(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("stop")


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(home: Path) -> AsyncIterator[Kernel]:
    async with running_kernel(home, WORLD) as kernel:
        yield kernel


@pytest_asyncio.fixture(loop_scope="module")
async def api(kernel: Kernel) -> AsyncIterator[httpx.AsyncClient]:
    async with kernel_api(kernel) as client:
        await eventually(lambda: all_healthy(client), timeout=120)
        yield client


async def process_on(api: httpx.AsyncClient, device: str) -> dict[str, Any] | None:
    running = (await api.get("/processes")).json()
    return next((p for p in running if device in p["devices"]), None)


async def process(api: httpx.AsyncClient, process_id: int) -> dict[str, Any]:
    listed = (await api.get("/processes", params={"all": "true"})).json()
    return next(p for p in listed if p["id"] == process_id)


async def stop_and_check_still(api: httpx.AsyncClient, kernel: Kernel, text: str, robot: str) -> str:
    """Say ``text``; once handled, the robot's pose must not change over 0.5 s. Returns the reply."""
    event_id = await chat(api, text)
    await eventually(lambda: handled(api, event_id), timeout=20)
    first = await device_state(kernel, robot)
    await asyncio.sleep(0.5)
    later = await device_state(kernel, robot)
    travelled = abs(later["x"] - first["x"]) + abs(later["y"] - first["y"])
    assert travelled < STILL, f"the {robot} moved {travelled:.3f} m in the 0.5 s after the stop was handled"
    said = [u["text"] for u in await updates_of(api, event_id) if u["kind"] == "kernel_reply"]
    assert said, "the stop got no reply"
    return " ".join(said)


async def test_stop_the_dog_terminates_the_walk_that_holds_it(
    api: httpx.AsyncClient, kernel: Kernel, walking_dog: WalkingDog
) -> None:
    walk = await walking_dog("walk the dog forward two meters")

    reply = await stop_and_check_still(api, kernel, "okay, enough, halt the dog", "dog")

    assert (await process(api, walk["id"]))["state"] == "terminated"
    assert "dog" in reply and "walk the dog forward two meters" in reply.lower()
    assert (await device_state(kernel, "dog"))["x"] < 1.9  # it did not walk its two metres


async def test_a_bare_stop_stops_the_moving_robot_and_then_the_music(
    api: httpx.AsyncClient, kernel: Kernel, walking_dog: WalkingDog
) -> None:
    music = await chat(api, "play some music")
    await eventually(lambda: handled(api, music))
    await eventually(lambda: _playing(kernel))
    walk = await walking_dog("walk the dog back one meter")

    reply = await stop_and_check_still(api, kernel, "stop", "dog")

    assert (await process(api, walk["id"]))["state"] == "terminated"
    assert (await device_state(kernel, "spotify"))["is_playing"] is False
    # The robot is stopped (and named) first, the music after it.
    assert reply.index("dog") < reply.index("Spotify"), reply  # a product is named as one


async def test_a_question_is_answered_while_a_search_holds_the_robot_and_stop_ends_the_search(
    api: httpx.AsyncClient, kernel: Kernel
) -> None:
    await chat(api, "search for a person with the turtlebot")
    search = await eventually(lambda: process_on(api, "turtlebot"))

    asked = await chat(api, "is the turtlebot docked?")
    await eventually(lambda: handled(api, asked))
    said = await updates_of(api, asked)
    kinds = [u["kind"] for u in said]
    assert "process_launched" not in kinds and "notice" not in kinds, said
    answer = next(u["text"] for u in said if u["kind"] == "kernel_reply")
    assert answer.startswith("No, the turtlebot is not docked"), answer
    assert "rad" not in answer

    battery = await chat(api, "how charged is the turtlebot?")
    await eventually(lambda: handled(api, battery))
    assert any("battery is at" in u["text"] for u in await updates_of(api, battery))
    assert (await process(api, search["id"]))["state"] == "running"  # the question took no lease

    await stop_and_check_still(api, kernel, "stop the turtlebot", "turtlebot")
    assert (await process(api, search["id"]))["state"] == "terminated"


async def test_chat_wait_exits_non_zero_when_its_launch_is_refused(
    kernel: Kernel, home: Path, walking_dog: WalkingDog
) -> None:
    walk = await walking_dog("walk the dog forward two meters")
    # A launch waits behind a short plan that holds its device (processes/queue_behind.py); with
    # no wait allowed, the held dog is refused at once, which is what this exit code is about.
    kernel.manager.queue_wait = 0
    try:
        command = [ROSAOS, "chat", "-c", str(home / "rosaos.toml"), "--url", kernel.url]
        refused = await _run([*command, "-m", "turn the dog left", "--wait"])
        assert refused.returncode != 0, refused.stdout + refused.stderr
        assert "dog is held by process" in refused.stdout
        stopped = await _run([*command, "-m", "stop the dog", "--wait"])
        assert stopped.returncode == 0, stopped.stdout + stopped.stderr
    finally:
        kernel.manager.queue_wait = QUEUE_WAIT
        await kernel.manager.terminate(walk["id"])


async def _playing(kernel: Kernel) -> bool:
    return bool((await device_state(kernel, "spotify"))["is_playing"])


async def _run(command: list[Any]) -> subprocess.CompletedProcess[str]:
    """The CLI in a thread: the kernel under test runs on this event loop and must keep answering."""
    return await asyncio.to_thread(subprocess.run, command, capture_output=True, text=True, timeout=120)
