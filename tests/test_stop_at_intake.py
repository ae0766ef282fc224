"""A person's "stop" stops the robot at intake, while the kernel's model is still busy with a turn.

The kernel and the process agent are the scripted ``FunctionModel``s of ``kernel_scripts.py``:
the process walks the dog (2 m at 0.12 m/s, about 17 s); the kernel is then kept busy by a turn
that takes 8 s ("slow 8"). "stop the dog" arrives during that turn. Before the fast path the
stop waited its turn and the dog walked on for those seconds; now the dog is stopped (its
``safe_stop`` answered) under the issue's 0.5 s after intake, asserted with a 2x margin for a
loaded CI machine on the kernel's own clock. That is measured to the moment the robot stops, not
to the end of the whole stop: the walk's worker process may take longer to exit on a busy
machine, and the robot is already still by then. The test's polling over MCP sees the dog still
long before the turn ends, while the stop's event is still queued, and the kernel answers it
afterwards with what the intake stop did. Real kernel, worker subprocess, ROS simulator over MCP
HTTP.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import httpx
import pytest
import pytest_asyncio

from rosaos.kernel.runtime import Kernel

from .e2e_support import (
    all_healthy,
    chat,
    device_state,
    eventually,
    handled,
    kernel_api,
    scripted_kernel,
    updates_of,
)

pytestmark = pytest.mark.asyncio(loop_scope="module")
WalkingDog = Callable[[str], Awaitable[dict[str, Any]]]

WORLD = """
[devices.dog]
driver = "ros"
description = "Hiwonder PuppyPi quadruped robot dog"
profile = "puppypi"
"""

SLOW_TURN = 8.0
"""Seconds the kernel's model spends on the turn the stop arrives during."""
STOP_BOUND = 0.5
"""The issue's bound: the robot stops within 0.5 s of the stop being received (intake to the
dog's ``safe_stop`` answered)."""
MARGIN = 2.0
"""Two cores shared with other jobs: the bound is asserted doubled, still far below ``SLOW_TURN``."""
STILL = 0.02
"""Metres the pose may drift in 0.5 s and still count as stopped (odometry noise, one last tick)."""


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[Kernel]:
    async with scripted_kernel(tmp_path_factory.mktemp("stop-at-intake"), WORLD) as kernel:
        yield kernel


@pytest_asyncio.fixture(loop_scope="module")
async def api(kernel: Kernel) -> AsyncIterator[httpx.AsyncClient]:
    async with kernel_api(kernel) as client:
        await eventually(lambda: all_healthy(client), timeout=120)
        yield client


async def test_stop_the_dog_stops_it_at_intake_while_the_kernel_is_mid_turn(
    api: httpx.AsyncClient, kernel: Kernel, walking_dog: WalkingDog
) -> None:
    walk = await walking_dog('dog: call move_distance {"meters": 2}')
    busy = await chat(api, f"slow {SLOW_TURN:g}")
    await asyncio.sleep(0.5)  # the kernel's model is now inside its 8 s turn
    assert not await handled(api, busy)

    sent = time.monotonic()
    stop = await chat(api, "stop the dog")
    while abs((await device_state(kernel, "dog"))["linear"]) > 0.0:
        assert time.monotonic() - sent < SLOW_TURN, "the stop waited for the kernel's turn"
        await asyncio.sleep(0.02)
    stopped_after = time.monotonic() - sent
    first = await device_state(kernel, "dog")
    await asyncio.sleep(0.5)
    later = await device_state(kernel, "dog")

    assert stopped_after < SLOW_TURN / 2, f"the dog stopped only {stopped_after:.2f} s after the stop"
    said = await updates_of(api, stop)
    intake = [u["data"] for u in said if u["kind"] == "tool_call" and u["data"].get("at_intake")]
    assert intake, f"no stop at intake among {said}"
    halted, took = intake[0]["safe_stop_seconds"]["dog"], intake[0]["seconds"]
    print(
        f"the dog's safe_stop answered {halted:.3f} s after intake (the whole stop, its process ended: "
        f"{took:.3f} s); the test saw the dog still {stopped_after:.3f} s after sending"
    )
    assert halted < STOP_BOUND * MARGIN, f"the dog was stopped only {halted:.2f} s after intake"
    assert took < SLOW_TURN / 2, f"the stop at intake took {took:.2f} s: it waited for something"
    assert abs(later["x"] - first["x"]) < STILL, "the dog walked on after its stop"
    assert not await handled(api, stop), "the kernel was still busy: this stop came from intake"
    listed = (await api.get("/processes", params={"all": "true"})).json()
    assert next(p for p in listed if p["id"] == walk["id"])["state"] == "terminated"
    await eventually(lambda: handled(api, stop), timeout=60)  # the kernel still handles it, after its turn


async def test_the_kernel_still_answers_the_stop_with_what_was_stopped(
    api: httpx.AsyncClient, walking_dog: WalkingDog
) -> None:
    await walking_dog('dog: call move_distance {"meters": 2}')
    stop = await chat(api, "stop: dog")
    await eventually(lambda: handled(api, stop), timeout=30)
    said = await updates_of(api, stop)
    intake = [u for u in said if u["kind"] == "tool_call" and u["data"].get("at_intake")]
    reply = next(u["text"] for u in said if u["kind"] == "kernel_reply")
    assert intake, said
    assert "Stopped the dog: it was doing" in reply, reply  # the kernel's stop tool told what intake did


async def test_a_sentence_that_is_not_a_stop_is_left_to_the_kernel(api: httpx.AsyncClient) -> None:
    event = await chat(api, "don't stop the dog")
    await eventually(lambda: handled(api, event), timeout=30)
    said = await updates_of(api, event)
    assert not any(u["data"].get("at_intake") for u in said if u["kind"] == "tool_call"), said


async def test_a_name_the_user_gave_stops_at_intake_too(
    api: httpx.AsyncClient, kernel: Kernel, walking_dog: WalkingDog
) -> None:
    kernel.memory.save_note("alias", "rex", "the dog", "call the dog Rex")
    walk = await walking_dog('dog: call move_distance {"meters": 2}')
    busy = await chat(api, f"slow {SLOW_TURN:g}")
    await asyncio.sleep(0.5)  # the kernel's model is now inside its turn: only intake can stop now
    stop = await chat(api, "Rex, stop!")
    await eventually(lambda: _stopped_at_intake(api, stop), timeout=SLOW_TURN / 2)
    assert not await handled(api, busy), "the kernel's turn ended first: the stop did not come from intake"
    listed = (await api.get("/processes", params={"all": "true"})).json()
    assert next(p for p in listed if p["id"] == walk["id"])["state"] == "terminated"
    await eventually(lambda: handled(api, stop), timeout=60)


async def _stopped_at_intake(api: httpx.AsyncClient, event_id: int) -> bool:
    said = await updates_of(api, event_id)
    return any(u["kind"] == "tool_call" and u["data"].get("at_intake") for u in said)
