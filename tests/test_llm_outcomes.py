"""With a model in the loop, success is the devices' word: ``rosaos chat --wait`` exits 0 only if it shows.

The real kernel on loopback, its worker subprocesses and two Tapo simulators over MCP HTTP; the
kernel and every process agent talk to a scripted OpenAI-compatible server (``scripted_llm.py``)
with ``prefer_local = false``, so the "model" handles commands the offline engine knows. The
process agent's script lies in a different way for each sentence; ``rosaos chat -m … --wait``
runs as a subprocess, as a person or a script would run it (issue 22, "Honest outcomes").
"""

from __future__ import annotations

import asyncio
import json
import subprocess
from collections.abc import AsyncIterator, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
import pytest_asyncio

from rosaos.kernel.runtime import Kernel

from .cli_process import ROSAOS
from .e2e_support import TWO_LIGHTS, device_state, eventually, kernel_api, running_kernel
from .scripted_llm import (
    Message,
    ScriptedLLM,
    models_table,
    say,
    scripted_llm,
    task_of,
    tool_call,
    tool_results,
)

pytestmark = [pytest.mark.e2e, pytest.mark.asyncio(loop_scope="module")]

LAUNCHES = {
    "turn on the kitchen light": "Turn on the kitchen light.",
    "turn off the living room lamp": "Turn off the living room lamp.",
    "make the kitchen light ultraviolet": "Set the kitchen light's colour to ultraviolet.",
    "dim the living room lamp": "Dim the living room lamp to 10 %.",
}
"""What the scripted kernel launches for each sentence (one device each, named in the task)."""


def answer(role: str, messages: list[Message], tools: list[str]) -> Message:
    if role == "kernel":
        return kernel_turn(messages)
    task, results = task_of(messages), tool_results(messages)
    if task.startswith("Turn on"):  # honest: the call, then the report beside it
        return tool_call("turn_on", {}, "The kitchen light is on.") if not results else say("It is on.")
    if task.startswith("Turn off"):  # no call at all, and says it is done
        return say("Done, the living room lamp is off.")
    if task.startswith("Set"):  # its only call fails, and it says it is done anyway
        return tool_call("set_color_name", {"name": "ultraviolet"}) if not results else say("Done.")
    if task.startswith("Dim"):  # reads the state, and says it changed it
        return tool_call("get_state", {}) if not results else say("Dimmed to 10 %.")
    return say("I cannot do that.")


def kernel_turn(messages: list[Message]) -> Message:
    last = messages[-1]
    if last.get("role") == "tool":
        return say("On it.")
    text = str(last.get("content") or "").lower()
    for sentence, task in LAUNCHES.items():
        if sentence in text and "callback" not in text:
            device = "kitchen_light" if "kitchen" in sentence else "living_room_lamp"
            return tool_call("launch_process", {"task": task, "devices": [device]}, "On it.")
    return say("That did not work." if "callback" in text else "Sorry?")


@pytest.fixture(scope="module")
def llm() -> Iterator[ScriptedLLM]:
    with scripted_llm(answer) as script:
        yield script


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(tmp_path_factory: pytest.TempPathFactory, llm: ScriptedLLM) -> AsyncIterator[Kernel]:
    home = tmp_path_factory.mktemp("llm-outcomes")
    async with running_kernel(home, TWO_LIGHTS + models_table(llm.url)) as kernel:
        kernel.test_home = home  # type: ignore[attr-defined]
        yield kernel


@pytest_asyncio.fixture(loop_scope="module")
async def api(kernel: Kernel) -> AsyncIterator[httpx.AsyncClient]:
    async with kernel_api(kernel) as client:
        yield client


async def chat_wait(kernel: Kernel, text: str) -> tuple[int, dict[str, Any]]:
    """``rosaos chat -m TEXT --wait --json``: its exit code and its summary."""
    home: Path = kernel.test_home  # type: ignore[attr-defined]
    command = [
        ROSAOS,
        "chat",
        "-c",
        str(home / "rosaos.toml"),
        "--url",
        kernel.url,
        "-m",
        text,
        "--wait",
        "--json",
    ]
    done = await asyncio.to_thread(subprocess.run, command, capture_output=True, text=True, timeout=180)
    assert done.stdout.strip(), done.stderr
    return done.returncode, json.loads(done.stdout)


async def test_a_change_the_device_shows_ends_ok_and_exits_0(kernel: Kernel, llm: ScriptedLLM) -> None:
    code, summary = await chat_wait(kernel, "turn on the kitchen light")
    assert code == 0, summary
    assert [p["status"] for p in summary["processes"]] == ["ok"]
    assert (await device_state(kernel, "kitchen_light"))["on"] is True
    assert any(r.role == "process" for r in llm.requests), "the process agent must be the scripted model"


async def test_a_worker_that_calls_no_tool_is_unverified_and_exits_non_zero(kernel: Kernel) -> None:
    code, summary = await chat_wait(kernel, "turn off the living room lamp")
    assert code == 1, summary
    [process] = summary["processes"]
    assert process["status"] == "unverified"
    assert "no successful device call" in process["error"]
    assert (await device_state(kernel, "living_room_lamp"))["on"] is True


async def test_a_worker_whose_only_call_failed_is_an_error_and_exits_non_zero(kernel: Kernel) -> None:
    code, summary = await chat_wait(kernel, "make the kitchen light ultraviolet")
    assert code == 1, summary
    [process] = summary["processes"]
    assert process["status"] == "error"
    assert process["error"].startswith("kitchen_light: set_color_name failed:")


async def test_a_change_task_whose_calls_only_read_is_unverified_and_exits_non_zero(
    kernel: Kernel, api: httpx.AsyncClient
) -> None:
    brightness = (await device_state(kernel, "living_room_lamp"))["brightness"]
    code, summary = await chat_wait(kernel, "dim the living room lamp")
    assert code == 1, summary
    [process] = summary["processes"]
    assert process["status"] == "unverified"
    assert "only read state (living_room_lamp.get_state)" in process["error"]
    assert (await device_state(kernel, "living_room_lamp"))["brightness"] == brightness
    # The process list says so too, not only the chat command.
    listed = await eventually(lambda: _process(api, process["id"]))
    assert listed["state"] == "unverified"


async def _process(api: httpx.AsyncClient, process_id: int) -> dict[str, Any] | None:
    return next(
        (p for p in (await api.get("/processes", params={"all": "true"})).json() if p["id"] == process_id),
        None,
    )
