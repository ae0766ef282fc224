"""An LLM kernel stops a held robot with the ``stop`` kernel tool, and reads state with ``device_state``.

The kernel and the process agent are the scripted ``FunctionModel``s of ``kernel_scripts.py``: the
process walks the dog with ``move_distance``, and the kernel, told "stop: dog", calls ``stop``
(no lease) while that process holds the dog. Real kernel, worker subprocess, ROS simulator.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from typing import Any

import httpx
import pytest
import pytest_asyncio

from rosaos.kernel.runtime import Kernel

from .e2e_support import device_state, eventually, kernel_api, scripted_kernel

pytestmark = pytest.mark.asyncio(loop_scope="module")

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
        await eventually(lambda: _all_healthy(client), timeout=120)
        yield client


async def chat(api: httpx.AsyncClient, text: str) -> int:
    response = await api.post("/chat", json={"text": text})
    assert response.status_code == 202, response.text
    return int(response.json()["id"])


async def handled(api: httpx.AsyncClient, event_id: int) -> bool:
    return bool((await api.get(f"/events/{event_id}")).json().get("handled"))


async def updates_of(api: httpx.AsyncClient, event_id: int) -> list[dict[str, Any]]:
    updates = (await api.get("/updates", params={"after": 0, "limit": 1000})).json()["updates"]
    return [u for u in updates if u.get("event_id") == event_id]


async def walking(api: httpx.AsyncClient, kernel: Kernel) -> dict[str, Any] | None:
    running = [p for p in (await api.get("/processes")).json() if "dog" in p["devices"]]
    if running and abs((await device_state(kernel, "dog"))["linear"]) > 0.01:
        return running[0]
    return None


async def test_the_llm_kernel_stops_the_held_dog_with_the_stop_tool(
    api: httpx.AsyncClient, kernel: Kernel
) -> None:
    await chat(api, 'dog: call move_distance {"meters": 2}')
    walk = await eventually(lambda: walking(api, kernel), timeout=120)

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


async def _all_healthy(api: httpx.AsyncClient) -> bool:
    return all(device["status"] == "healthy" for device in (await api.get("/devices")).json())
