"""An LLM kernel's timers: a scripted ``FunctionModel`` kernel calls set_timer, list_timers and
cancel_timer, and the fired timer's action reaches it as ``[Timer fired]`` and runs as a process.

Everything else is what ``rosaos up`` runs: event store, loop, process manager, worker
subprocesses, the Tapo simulator over MCP HTTP.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from typing import Any

import httpx
import pytest
import pytest_asyncio

from rosaos.kernel.runtime import Kernel

from .e2e_support import device_state, eventually, kernel_api, scripted_kernel

pytestmark = pytest.mark.asyncio(loop_scope="module")


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[Kernel]:
    async with scripted_kernel(tmp_path_factory.mktemp("timers")) as kernel:
        yield kernel


@pytest_asyncio.fixture(loop_scope="module")
async def api(kernel: Kernel) -> AsyncIterator[httpx.AsyncClient]:
    async with kernel_api(kernel) as client:
        yield client


async def reply_to(api: httpx.AsyncClient, text: str) -> str:
    event_id = int((await api.post("/chat", json={"text": text})).json()["id"])
    found: list[str] = []

    async def replied() -> bool:
        found[:] = [
            u["text"] for u in await updates(api) if u["kind"] == "kernel_reply" and u["event_id"] == event_id
        ]
        return bool(found)

    await eventually(replied)
    return found[0]


async def updates(api: httpx.AsyncClient) -> list[dict[str, Any]]:
    return list((await api.get("/updates", params={"after": 0, "limit": 1000})).json()["updates"])


async def test_a_timer_set_by_the_model_fires_once_and_its_action_runs(
    kernel: Kernel, api: httpx.AsyncClient
) -> None:
    reply = await reply_to(api, "timer 1: kitchen_light: call turn_on {}")
    assert "'state': 'pending'" in reply
    assert (await device_state(kernel, "kitchen_light"))["on"] is False

    async def light_on() -> bool:
        return bool((await device_state(kernel, "kitchen_light"))["on"])

    await eventually(light_on)
    fired = [u for u in await updates(api) if u["kind"] == "event" and u["data"]["kind"] == "timer_fired"]
    assert [u["data"]["payload"]["action"] for u in fired] == ["kitchen_light: call turn_on {}"]
    launches = [
        u
        for u in await updates(api)
        if u["kind"] == "process_launched" and u["event_id"] == fired[0]["event_id"]
    ]
    assert len(launches) == 1


async def test_the_model_lists_and_cancels_a_timer_and_it_never_runs(
    kernel: Kernel, api: httpx.AsyncClient
) -> None:
    # Ten minutes: on a loaded machine a 2 s timer fired before "list timers" was answered (CI).
    await reply_to(api, "timer 600: living_room_lamp: call turn_off {}")
    assert "living_room_lamp: call turn_off" in await reply_to(api, "list timers")
    assert "'state': 'cancelled'" in await reply_to(api, "cancel timer")
    await kernel.timers.fire_due()  # due or not, a cancelled timer has nothing to fire
    listed = (await api.get("/timers", params={"all": "true"})).json()["timers"]
    assert [t["state"] for t in listed if "living_room_lamp" in t["action"]] == ["cancelled"]
    assert (await device_state(kernel, "living_room_lamp"))["on"] is True
