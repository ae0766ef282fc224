"""A text-only model still answers "take a picture and tell me what you see", through describe_image.

The real kernel on loopback, a worker subprocess and the Reachy Mini simulator over MCP HTTP; the
kernel and the process agent are a scripted OpenAI-compatible server (``scripted_llm.py``) that
answers 400 to any request with an image part, as a local server without a vision tower does.
Two configurations (issue 22, "Vision as the paper does it"):

- ``vision`` unset, the default for an ``openai-compatible`` endpoint: no image part is ever sent;
  ``take_picture`` gives the path and ``describe_image`` says what is in it.
- ``vision = true``, wrongly declared: the picture goes with ``take_picture``'s result, the server
  answers 400, the worker sends the request again once without it, and the task still completes.
"""

from __future__ import annotations

import asyncio
import json
import re
import subprocess
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import httpx
import pytest
import pytest_asyncio

from .cli_process import ROSAOS
from .e2e_support import kernel_api, running_kernel
from .scripted_llm import Message, models_table, say, scripted_llm, task_of, tool_call, tool_results

pytestmark = [pytest.mark.e2e, pytest.mark.asyncio(loop_scope="module")]

WORLD = '\n[devices.reachy]\ndriver = "reachy"\ndescription = "Reachy Mini desk robot with a camera"\n'
SENTENCE = "take a picture and tell me what you see"
TASK = "Take a picture with the Reachy's camera and describe what you see."


def answer(role: str, messages: list[Message], tools: list[str]) -> Message:
    if role == "kernel":
        last = messages[-1]
        if last.get("role") == "tool":
            return say("On it.")
        text = str(last.get("content") or "")
        if SENTENCE in text.lower() and "callback" not in text.lower():
            return tool_call("launch_process", {"task": TASK, "devices": ["reachy"]}, "Let me look.")
        return say("Here is what the camera saw.")
    assert task_of(messages) == TASK, task_of(messages)
    results = tool_results(messages)
    if not results:
        return tool_call("take_picture", {})
    if len(results) == 1:  # the path is in the result's text, with or without the picture beside it
        found = re.search(r'"path": ?"([^"]+)"', results[0])
        assert found, results[0]
        path = found.group(1)
        return tool_call("describe_image", {"path": path, "question": "What is in the picture?"})
    return say(f"I see: {results[1][:200]}")


async def run_chat(home: Path, url: str) -> tuple[int, dict[str, Any]]:
    command = [
        ROSAOS,
        "chat",
        "-c",
        str(home / "rosaos.toml"),
        "--url",
        url,
        "-m",
        SENTENCE,
        "--wait",
        "--json",
    ]
    done = await asyncio.to_thread(subprocess.run, command, capture_output=True, text=True, timeout=240)
    assert done.stdout.strip(), done.stderr
    return done.returncode, json.loads(done.stdout)


@pytest_asyncio.fixture(loop_scope="module")
async def home(tmp_path: Path) -> AsyncIterator[Path]:
    yield tmp_path


@pytest.mark.parametrize("declared_vision", [None, True], ids=["vision-unset", "vision-wrongly-declared"])
async def test_take_a_picture_and_tell_me_completes_with_a_model_that_refuses_images(
    home: Path, declared_vision: bool | None
) -> None:
    with scripted_llm(answer, reject_images=True) as llm:
        world = WORLD + models_table(llm.url, vision=declared_vision)
        async with running_kernel(home, world) as kernel, kernel_api(kernel) as api:
            code, summary = await run_chat(home, kernel.url)
            assert code == 0, summary
            [process] = summary["processes"]
            assert process["status"] == "ok", process
            tools = [(r["tool"], r["ok"]) for r in await _receipts(api, process["id"])]
            assert tools == [("take_picture", True), ("describe_image", True)]
    asked = [r for r in llm.requests if r.role == "process"]
    refused = [r for r in asked if r.status == 400]
    if declared_vision:
        # The picture went once, was refused, and the same request went again without it.
        assert len(refused) == 1 and refused[0].has_image
        after = asked[asked.index(refused[0]) + 1 :]
        assert after and not any(r.has_image for r in after)
        assert any("this model refused image input" in json.dumps(r.messages) for r in after)
    else:
        assert not refused and not any(r.has_image for r in asked)
    assert asked[-1].status == 200 and len(tool_results(asked[-1].messages)) == 2


async def _receipts(api: httpx.AsyncClient, process_id: int) -> list[dict[str, Any]]:
    entries = (await api.get("/activity", params={"since": 0})).json()["entries"]
    return [e for e in entries if e.get("process_id") == process_id]
