"""The kernel end to end: real device servers, real worker subprocesses, the real HTTP API.

The kernel and the process agents run scripted ``FunctionModel``s (tests/kernel_scripts.py), so
every other part is the one ``rosaos up`` runs: the event store, the kernel loop, the process
manager with its leases, the worker pool, the Tapo simulator served over MCP HTTP.
"""

from __future__ import annotations

import asyncio
import os
import shutil
import signal
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import httpx
import pytest
import pytest_asyncio
from playwright.async_api import async_playwright

from rosaos.kernel.runtime import Kernel, KernelError, _bind_or_explain
from rosaos.kernel.stop_tools import STOP_TOOL_NAMES
from rosaos.kernel.tools import KERNEL_TOOL_NAMES
from rosaos.memory.memory_tools import MEMORY_TOOL_NAMES
from rosaos.models.tool_schemas import KERNEL_HIDDEN
from rosaos.timers.timer_tools import TIMER_TOOL_NAMES

from .e2e_support import device_state, eventually, kernel_api, scripted_kernel

pytestmark = pytest.mark.asyncio(loop_scope="module")


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[Kernel]:
    async with scripted_kernel(tmp_path_factory.mktemp("kernel")) as kernel:
        yield kernel


@pytest_asyncio.fixture(loop_scope="module")
async def api(kernel: Kernel) -> AsyncIterator[httpx.AsyncClient]:
    async with kernel_api(kernel) as client:
        yield client


async def updates_for(api: httpx.AsyncClient, after: int = 0) -> list[dict[str, Any]]:
    page = (await api.get("/updates", params={"after": after, "limit": 1000})).json()
    return list(page["updates"])


async def chat(api: httpx.AsyncClient, text: str) -> int:
    response = await api.post("/chat", json={"text": text})
    assert response.status_code == 202, response.text
    return int(response.json()["id"])


async def settled(api: httpx.AsyncClient) -> bool:
    """No running process and no pending event."""
    processes = (await api.get("/processes")).json()
    pending = (await api.get("/health")).json()["pending_events"]
    return not any(p["state"] == "running" for p in processes) and pending == 0


async def test_chat_turns_on_the_kitchen_light_through_a_process(
    kernel: Kernel, api: httpx.AsyncClient
) -> None:
    assert (await device_state(kernel, "kitchen_light"))["on"] is False
    event_id = await chat(api, "turn on the kitchen light")

    await eventually(lambda: _state_is(kernel, "kitchen_light", "on", True))
    await eventually(lambda: settled(api))
    updates = await updates_for(api)
    ours = [u for u in updates if u["event_id"] == event_id]
    kinds = [u["kind"] for u in ours]
    assert kinds[0] == "event" and "process_launched" in kinds and "kernel_reply" in kinds
    launch = next(u for u in ours if u["kind"] == "tool_call")
    assert launch["data"] == {
        "tool": "launch_process",
        "args": {"task": "call turn_on {}", "devices": ["kitchen_light"]},
    }
    process_id = next(u for u in ours if u["kind"] == "process_launched")["data"]["process_id"]
    callback = next(
        u
        for u in updates
        if u["kind"] == "event" and u["data"].get("payload", {}).get("process_id") == process_id
    )
    assert callback["data"]["kind"] == "worker_callback"
    assert callback["data"]["payload"]["status"] == "ok"
    replies = [
        u["text"] for u in updates if u["kind"] == "kernel_reply" and u["event_id"] == callback["event_id"]
    ]
    # An ok callback with nothing to decide is relayed in the process's words, with no kernel request.
    assert replies == [callback["data"]["payload"]["output"]] == ["done 1 calls"]
    assert any(u["kind"] == "process_ended" and u["data"]["process_id"] == process_id for u in updates)


async def test_the_kernel_is_offered_its_process_timer_stop_and_memory_tools_and_no_device_tool(
    kernel: Kernel, api: httpx.AsyncClient
) -> None:
    from .kernel_scripts import KERNEL_TOOLS_SEEN

    await chat(api, "slow 0")
    await eventually(lambda: settled(api))
    # Less the tools whose answer an LLM has in another form (the prompt's device list, recall).
    assert (
        set(KERNEL_TOOL_NAMES) | set(TIMER_TOOL_NAMES) | set(STOP_TOOL_NAMES) | set(MEMORY_TOOL_NAMES)
    ) - KERNEL_HIDDEN == KERNEL_TOOLS_SEEN


async def test_a_launch_without_a_task_gives_the_process_the_users_sentence_as_said(
    kernel: Kernel, api: httpx.AsyncClient
) -> None:
    # Issue 22: copying the sentence into the task cost a local model a third of the kernel's decoding.
    sentence = 'call set_brightness {"brightness": 37}'
    event_id = await chat(api, sentence)
    await eventually(lambda: _state_is(kernel, "kitchen_light", "brightness", 37))
    await eventually(lambda: settled(api))
    ours = [u for u in await updates_for(api) if u["event_id"] == event_id]
    launch = next(u for u in ours if u["kind"] == "tool_call")
    assert launch["data"]["args"] == {"devices": ["kitchen_light"]}
    process_id = next(u for u in ours if u["kind"] == "process_launched")["data"]["process_id"]
    ended = (await api.get("/processes", params={"all": "true"})).json()
    process = next(p for p in ended if p["id"] == process_id)
    assert process["task"] == sentence


async def test_a_launch_without_a_task_for_an_event_that_is_no_sentence_of_the_user_is_refused(
    api: httpx.AsyncClient,
) -> None:
    before = max((u["id"] for u in await updates_for(api)), default=0)
    await chat(api, "timer 0.1: call turn_off {}")  # the timer's event is no sentence of the user's

    async def refusal() -> str | None:
        notices = [u["text"] for u in await updates_for(api, before) if u["kind"] == "notice"]
        return next((text for text in notices if text.startswith("launch refused:")), None)

    assert "give the task" in await eventually(refusal)


async def test_a_second_kernel_on_the_same_port_says_what_is_running(kernel: Kernel) -> None:
    port = int(kernel.url.rsplit(":", 1)[1])
    with pytest.raises(KernelError, match=r"rosaOS .* is already running at http://127\.0\.0\.1:\d+/"):
        await _bind_or_explain("127.0.0.1", port, kernel.token)


async def _state_is(kernel: Kernel, device: str, key: str, value: Any) -> bool:
    return (await device_state(kernel, device)).get(key) == value


async def test_a_held_exclusive_device_is_refused_naming_the_holder(
    kernel: Kernel, api: httpx.AsyncClient
) -> None:
    await eventually(lambda: settled(api))
    event_id = await chat(api, "kitchen_light: sleep 2; kitchen_light: call turn_off {}")
    await eventually(lambda: settled(api))
    ours = [u for u in await updates_for(api) if u["event_id"] == event_id]
    launched = [u for u in ours if u["kind"] == "process_launched"]
    refused = [u for u in ours if u["kind"] == "notice" and u["text"].startswith("launch refused")]
    assert len(launched) == 1 and len(refused) == 1
    holder = launched[0]["data"]["process_id"]
    assert f"process {holder}" in refused[0]["text"] and "sleep 2" in refused[0]["text"]


async def test_two_processes_run_at_once_on_two_devices(kernel: Kernel, api: httpx.AsyncClient) -> None:
    await eventually(lambda: settled(api))
    event_id = await chat(
        api,
        'kitchen_light: sleep 1\ncall turn_off {}; living_room_lamp: sleep 1\ncall set_brightness {"brightness": 25}',
    )

    async def both_running() -> bool:
        running = [p for p in (await api.get("/processes")).json() if p["state"] == "running"]
        return len(running) == 2

    await eventually(both_running)
    await eventually(lambda: settled(api))
    ours = [u for u in await updates_for(api) if u["event_id"] == event_id]
    assert len([u for u in ours if u["kind"] == "process_launched"]) == 2
    assert (await device_state(kernel, "kitchen_light"))["on"] is False
    assert (await device_state(kernel, "living_room_lamp"))["brightness"] == 25


async def test_a_worker_killed_mid_task_reports_crashed_and_releases_its_lease(
    kernel: Kernel, api: httpx.AsyncClient
) -> None:
    await eventually(lambda: settled(api))
    await chat(api, "kitchen_light: sleep 30")

    async def running() -> dict[str, Any] | None:
        return next((p for p in (await api.get("/processes")).json() if p["state"] == "running"), None)

    process = await eventually(running)
    pid = await eventually(lambda: _worker_pid(api, process["id"]))
    os.kill(pid, signal.SIGKILL)

    async def crashed_callback() -> dict[str, Any] | None:
        return next(
            (
                u
                for u in await updates_for(api)
                if u["kind"] == "event"
                and u["data"].get("payload", {}).get("process_id") == process["id"]
                and u["data"]["payload"]["status"] == "crashed"
            ),
            None,
        )

    await eventually(crashed_callback)
    await eventually(lambda: settled(api))
    assert kernel.manager.leases.held_by(process["id"]) == []
    # The lease really is free: a new process gets the device.
    event_id = await chat(api, "kitchen_light: call turn_on {}")
    await eventually(lambda: settled(api))
    ours = [u for u in await updates_for(api) if u["event_id"] == event_id]
    assert [u["kind"] for u in ours].count("process_launched") == 1


async def _worker_pid(api: httpx.AsyncClient, process_id: int) -> int | None:
    for process in (await api.get("/processes")).json():
        if process["id"] == process_id:
            pid = process.get("worker_pid")
            return int(pid) if pid else None
    return None


CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


async def test_the_web_page_chats_with_the_kernel_and_shows_the_device_change(
    kernel: Kernel, api: httpx.AsyncClient, tmp_path: Path
) -> None:
    if CHROMIUM is None:
        pytest.skip("Chromium is not installed: ./scripts/test installs Debian's chromium package")
    await eventually(lambda: settled(api))
    # The lamp's card is its declared swatch: the colour's name and the brightness, as text.
    swatch = '.device-card[data-device="living_room_lamp"] .swatch-name'
    async with async_playwright() as playwright:
        browser = await playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        try:
            page = await browser.new_page()
            errors: list[str] = []
            page.on("pageerror", lambda error: errors.append(str(error)))
            await page.goto(kernel.login_link())
            await page.wait_for_selector("#app", state="visible")
            before = await (await page.wait_for_selector(swatch)).inner_text()
            assert not before.endswith(", 10 %"), before  # earlier tests of this module set it

            await page.fill("#chat-input", 'living_room_lamp: call set_brightness {"brightness": 10}')
            await page.press("#chat-input", "Enter")

            await page.wait_for_selector(f"{swatch}:has-text(', 10 %')", timeout=30_000)
            await page.wait_for_selector("#chat-log .msg-kernel", timeout=30_000)
            await page.screenshot(path=str(tmp_path / "web-page.png"), full_page=True)

            # The emergency stop latches from the page and is reset from it, after a confirmation.
            await page.click("#estop")
            await page.wait_for_selector("#estop-banner", state="visible")
            assert (await api.get("/estop")).json()["latched"] is True
            page.on("dialog", lambda dialog: asyncio.ensure_future(dialog.accept()))
            await page.click("#estop-reset")
            await page.wait_for_selector("#estop-banner", state="hidden")
            assert (await api.get("/estop")).json()["latched"] is False
            assert errors == []
        finally:
            await browser.close()


async def test_the_emergency_stop_kills_processes_stops_devices_and_latches(
    kernel: Kernel, api: httpx.AsyncClient
) -> None:
    await eventually(lambda: settled(api))
    await chat(api, "kitchen_light: sleep 30")
    await eventually(lambda: _running_count(api))

    report = (await api.post("/estop", json={"reason": "test"})).json()
    assert report["latched"] is True
    assert len(report["terminated"]) == 1
    assert {d["name"]: d["ok"] for d in report["devices"]} == {
        "kitchen_light": True,
        "living_room_lamp": True,
    }
    await eventually(lambda: settled(api))

    refused_event = await chat(api, "kitchen_light: call turn_on {}")
    await eventually(lambda: settled(api))
    notices = [
        u["text"] for u in await updates_for(api) if u["event_id"] == refused_event and u["kind"] == "notice"
    ]
    assert len(notices) == 1
    assert "emergency stop is latched" in notices[0]

    await api.post("/estop/reset")
    allowed_event = await chat(api, "kitchen_light: call turn_on {}")
    await eventually(lambda: settled(api))
    kinds = [u["kind"] for u in await updates_for(api) if u["event_id"] == allowed_event]
    assert "process_launched" in kinds


async def _running_count(api: httpx.AsyncClient) -> int:
    return len([p for p in (await api.get("/processes")).json() if p["state"] == "running"])
