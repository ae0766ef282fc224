"""An LLM kernel stops a held robot with the ``stop`` kernel tool, and reads state with ``device_state``.

The kernel and the process agent are the scripted ``FunctionModel``s of ``kernel_scripts.py``: the
process walks the dog with ``move_distance``, and the kernel, told "stop: dog", calls ``stop``
(no lease) while that process holds the dog. Real kernel, worker subprocess, ROS simulator.
"""

from __future__ import annotations

import asyncio
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


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[Kernel]:
    async with scripted_kernel(tmp_path_factory.mktemp("llm-stop"), WORLD) as kernel:
        yield kernel


@pytest_asyncio.fixture(loop_scope="module")
async def api(kernel: Kernel) -> AsyncIterator[httpx.AsyncClient]:
    async with kernel_api(kernel) as client:
        # A launch on a device that is not healthy yet is refused: wait (the simulator boots slowly when busy).
        await eventually(lambda: all_healthy(client), timeout=120)
        yield client


async def test_the_llm_kernel_stops_the_held_dog_with_the_stop_tool(
    api: httpx.AsyncClient, kernel: Kernel, walking_dog: WalkingDog
) -> None:
    walk = await walking_dog('dog: call move_distance {"meters": 2}')

    stop = await chat(api, "stop: dog")
    await eventually(lambda: handled(api, stop), timeout=20)
    first = await device_state(kernel, "dog")
    await asyncio.sleep(0.5)
    later = await device_state(kernel, "dog")

    assert abs(later["x"] - first["x"]) < 0.02, "the dog kept walking after the stop was handled"
    listed = (await api.get("/processes", params={"all": "true"})).json()
    assert next(p for p in listed if p["id"] == walk["id"])["state"] == "terminated"
    said = await updates_of(api, stop)
    assert any(u["kind"] == "tool_call" and u["data"]["tool"] == "stop" for u in said)
    # Not refused: the stop needs no lease. (A turn that batched the stop with the walk's end,
    # which the stop at intake queued meanwhile, says "handled together with event N": no refusal.)
    refusals = [u for u in said if u["kind"] == "notice" and not u["text"].startswith("handled together")]
    assert refusals == [], said
    assert any("Stopped the dog" in u["text"] for u in said if u["kind"] == "kernel_reply")


async def test_the_llm_kernel_reads_state_without_a_process(api: httpx.AsyncClient) -> None:
    asked = await chat(api, "state dog")
    await eventually(lambda: handled(api, asked), timeout=20)
    said = await updates_of(api, asked)
    assert not any(u["kind"] == "process_launched" for u in said)
    reply = next(u["text"] for u in said if u["kind"] == "kernel_reply")
    assert "where it started" in reply and "rad" not in reply.replace("radians", "")
