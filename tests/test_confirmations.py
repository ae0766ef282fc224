"""Confirmation before risky actuation, end to end, on the offline engine.

The real kernel (its loop, the offline engine, the API), a real worker subprocess, and the ROS
driver on its rosbridge simulator: "move the turtlebot forward half a meter" pauses on a question;
"yes" in the chat runs it, "no" cancels it, silence cancels it; the lease is released each time.
"""

from __future__ import annotations

import asyncio
import io
from collections.abc import AsyncIterator
from typing import Any

import httpx
import pytest
import pytest_asyncio
from rich.console import Console

from rosaos.frontends.chat import send_and_wait
from rosaos.kernel.api.kernel_client import KernelClient
from rosaos.kernel.runtime import Kernel

from .e2e_support import device_state, eventually, kernel_api, running_kernel

pytestmark = pytest.mark.asyncio(loop_scope="module")

WORLD = """
[kernel]
pool_size = 1
confirm_timeout = 3

[devices.turtlebot]
driver = "ros"
confirm = ["move_distance"]
sim = { docked = false }
"""
ORDER = "move the turtlebot forward half a meter"


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[Kernel]:
    async with running_kernel(tmp_path_factory.mktemp("confirm"), WORLD) as kernel:
        yield kernel


@pytest_asyncio.fixture(loop_scope="module")
async def api(kernel: Kernel) -> AsyncIterator[httpx.AsyncClient]:
    async with kernel_api(kernel) as client:
        yield client


async def chat(api: httpx.AsyncClient, text: str) -> None:
    assert (await api.post("/chat", json={"text": text})).status_code == 202


async def pending_question(api: httpx.AsyncClient) -> dict[str, Any]:
    async def one() -> dict[str, Any] | None:
        items = (await api.get("/confirmations")).json()["confirmations"]
        return items[0] if items else None

    item: dict[str, Any] = await eventually(one)
    return item


async def ended(api: httpx.AsyncClient, process_id: int) -> dict[str, Any]:
    async def done() -> dict[str, Any] | None:
        for process in (await api.get("/processes", params={"all": "true"})).json():
            if process["id"] == process_id and process["state"] != "running":
                return dict(process)
        return None

    process: dict[str, Any] = await eventually(done)
    return process


async def lease_free(api: httpx.AsyncClient) -> bool:
    devices = {d["name"]: d for d in (await api.get("/devices")).json()}
    return devices["turtlebot"]["held_by"] == []


async def test_yes_in_the_chat_runs_the_move(api: httpx.AsyncClient, kernel: Kernel) -> None:
    x_before = (await device_state(kernel, "turtlebot"))["x"]
    await chat(api, ORDER)
    question = await pending_question(api)
    assert question["tool"] == "move_distance" and question["device"] == "turtlebot"
    assert question["question"] == "The turtlebot will move distance (meters 0.5). Go ahead?"
    assert (await device_state(kernel, "turtlebot"))["x"] == pytest.approx(x_before, abs=0.01)
    await chat(api, "yes")
    process = await ended(api, question["process_id"])
    assert process["state"] == "ok", process
    assert (await device_state(kernel, "turtlebot"))["x"] == pytest.approx(x_before + 0.5, abs=0.05)
    assert await lease_free(api)
    answered = (await api.get(f"/confirmations/{question['id']}")).json()
    assert answered["state"] == "yes"


async def test_no_in_the_chat_cancels_and_releases_the_lease(api: httpx.AsyncClient, kernel: Kernel) -> None:
    x_before = (await device_state(kernel, "turtlebot"))["x"]
    await chat(api, ORDER)
    question = await pending_question(api)
    await chat(api, "no")
    process = await ended(api, question["process_id"])
    assert process["state"] == "terminated", process
    assert (await device_state(kernel, "turtlebot"))["x"] == pytest.approx(x_before, abs=0.01)
    assert await lease_free(api)
    entries = (await api.get("/activity", params={"process": question["process_id"]})).json()["entries"]
    calls = [e for e in entries if e["safety"] is None]
    assert [(e["tool"], e["ok"]) for e in calls] == [("move_distance", False)]
    assert "the person said no" in calls[0]["error"]
    # The question and its answer are safety decisions of their own in the log (issue 22).
    decisions = sorted(e["safety"]["decision"] for e in entries if e["safety"] is not None)
    assert decisions == ["confirm_asked", "declined"]


async def test_silence_times_out_and_cancels(api: httpx.AsyncClient, kernel: Kernel) -> None:
    x_before = (await device_state(kernel, "turtlebot"))["x"]
    await chat(api, ORDER)
    question = await pending_question(api)
    process = await ended(api, question["process_id"])
    assert process["state"] == "terminated", process
    assert (await api.get(f"/confirmations/{question['id']}")).json()["state"] == "expired"
    assert (await device_state(kernel, "turtlebot"))["x"] == pytest.approx(x_before, abs=0.01)
    assert await lease_free(api)


async def test_the_web_buttons_answer_through_the_api(api: httpx.AsyncClient) -> None:
    await chat(api, ORDER)
    question = await pending_question(api)
    answered = await api.post(f"/confirmations/{question['id']}", json={"answer": "yes"})
    assert answered.status_code == 200 and answered.json()["state"] == "yes"
    again = await api.post(f"/confirmations/{question['id']}", json={"answer": "no"})
    assert again.status_code == 409 and "already yes" in again.text
    assert (await api.post("/confirmations/9999", json={"answer": "yes"})).status_code == 404
    assert (await ended(api, question["process_id"]))["state"] == "ok"


async def test_rosaos_chat_wait_shows_the_question_it_waits_on(
    api: httpx.AsyncClient, kernel: Kernel
) -> None:
    """`rosaos chat -m ... --wait` prints the confirmation its process asks, so the user knows to answer."""
    shown = io.StringIO()
    async with KernelClient(kernel.url, kernel.token, timeout=30) as client:
        waiting = asyncio.create_task(send_and_wait(client, ORDER, 30, Console(file=shown, width=200)))
        question = await pending_question(api)
        await chat(api, "yes")
        code, conversation = await waiting
    assert code == 0, conversation.summary()
    assert (
        f"confirm {question['id']}: The turtlebot will move distance (meters 0.5). Go ahead?"
        in shown.getvalue()
    )
