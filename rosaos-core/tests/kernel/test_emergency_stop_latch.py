"""The emergency-stop latch survives a kernel restart, and only a reset clears it.

Each test starts the real :class:`~rosaos.kernel.runtime.Kernel` on loopback (a world without
devices, no warm workers) more than once on one data directory, the way ``rosaos up`` is run
again after a stop. The kernel agent is a ``FunctionModel`` that launches a process for whatever
the user typed, so a refused launch shows as a ``launch refused`` notice. A kernel killed with
SIGKILL is tested end to end in ``tests/test_kernel_restart.py``.
"""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    RetryPromptPart,
    TextPart,
    ToolCallPart,
    ToolReturnPart,
    UserPromptPart,
)
from pydantic_ai.models.function import AgentInfo, FunctionModel

from rosaos.config import load_config
from rosaos.devices.world import World
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.runtime import EMERGENCY_STOP_KEY, Kernel, events_path

from .kernel_support import eventually

pytestmark = pytest.mark.slow


def launching_kernel() -> FunctionModel:
    """A kernel agent that asks ``launch_process`` for every user message, then says what it got."""

    async def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        last = messages[-1]
        assert isinstance(last, ModelRequest)
        for part in last.parts:
            if isinstance(part, ToolReturnPart):
                return ModelResponse(parts=[TextPart(part.model_response_str())])
            if isinstance(part, RetryPromptPart):
                return ModelResponse(parts=[TextPart(part.model_response())])
        said = next(str(p.content) for p in last.parts if isinstance(p, UserPromptPart))
        return ModelResponse(parts=[ToolCallPart("launch_process", {"task": said, "devices": []})])

    return FunctionModel(respond)


@contextlib.asynccontextmanager
async def kernel_api(home: Path) -> AsyncIterator[httpx.AsyncClient]:
    """Start a kernel on ``home/data`` and yield a client for its API; stop the kernel on exit."""
    config_file = home / "rosaos.toml"
    config_file.write_text(f'data_dir = "{home / "data"}"\n[kernel]\npool_size = 0\n')
    config = load_config(config_file)
    kernel = Kernel(config, World(instances={}, source=config_file), kernel_model=launching_kernel())
    url = await kernel.start(host="127.0.0.1", port=0)
    try:
        headers = {"Authorization": f"Bearer {kernel.token}"}
        async with httpx.AsyncClient(base_url=url, headers=headers, timeout=10) as client:
            yield client
    finally:
        await kernel.stop()


async def say(api: httpx.AsyncClient, text: str) -> list[dict[str, Any]]:
    """Type ``text``, wait until the kernel has handled it, and return the updates it caused."""
    event_id = (await api.post("/chat", json={"text": text})).json()["id"]

    async def handled() -> bool:
        return bool((await api.get(f"/events/{event_id}")).json()["handled"])

    await eventually(handled, within=30, message=f"event {event_id} to be handled")
    updates = (await api.get("/updates", params={"after": 0, "limit": 1000})).json()["updates"]
    return [update for update in updates if update["event_id"] == event_id]


async def test_a_latched_stop_is_still_latched_after_a_restart_until_a_person_resets_it(
    tmp_path: Path,
) -> None:
    async with kernel_api(tmp_path) as api:
        report = (await api.post("/estop", json={"reason": "robot near the stairs"})).json()
        assert (report["latched"], report["reason"], report["saved"]) == (True, "robot near the stairs", True)

    async with kernel_api(tmp_path) as api:
        assert (await api.get("/estop")).json() == {
            "latched": True,
            "reason": "robot near the stairs",
            "time": report["time"],
            "untold_hosts": [],
        }
        # An event that arrives while latched is handled: the kernel is told why nothing may run.
        updates = await say(api, "wave at the visitors")
        notices = [u["text"] for u in updates if u["kind"] == "notice"]
        assert len(notices) == 1
        assert "emergency stop is latched (robot near the stairs)" in notices[0]
        assert "rosaos estop --reset" in notices[0]
        assert (await api.get("/processes", params={"all": "true"})).json() == []

        reset = (await api.post("/estop/reset")).json()
        assert reset == {"latched": False, "reason": None, "time": None, "untold_hosts": []}

    async with kernel_api(tmp_path) as api:
        assert (await api.get("/estop")).json() == {
            "latched": False,
            "reason": None,
            "time": None,
            "untold_hosts": [],
        }


async def test_a_stored_latch_this_version_cannot_read_stays_latched(tmp_path: Path) -> None:
    store = await EventStore.open(events_path(tmp_path / "data"))
    await store.set_value(EMERGENCY_STOP_KEY, {"latched": True, "by": "an older rosaOS"})
    await store.close()

    async with kernel_api(tmp_path) as api:
        state = (await api.get("/estop")).json()
        assert state["latched"] is True
        assert "could not be read" in state["reason"]
        assert "an older rosaOS" in state["reason"]


async def test_a_reset_with_nothing_latched_says_nothing_on_the_updates_stream(tmp_path: Path) -> None:
    async with kernel_api(tmp_path) as api:
        before = (await api.get("/updates", params={"after": 0, "limit": 1000})).json()["updates"]
        reset = (await api.post("/estop/reset")).json()
        after = (await api.get("/updates", params={"after": 0, "limit": 1000})).json()["updates"]
    assert reset == {"latched": False, "reason": None, "time": None, "untold_hosts": []}
    assert after == before
