"""``rosaos chat -m … --wait`` exits non-zero when nothing it asked for was done (issue 20).

The kernel publishes how each turn ended as a typed ``outcome`` on its reply (``done``,
``refused``, ``not_understood``, ``needs_answer``, ``needs_confirmation``): the offline engine sets
it where it decides, an LLM kernel's turn is ``refused`` when every tool call it made was refused.
The CLI maps it to its exit code (1 refused or failed, 4 not understood or waiting for an answer)
and prints one line on stderr saying what would work. Real kernel on loopback with two Tapo
simulators; the CLI through typer's runner (the process boundary is checked once, at the end).
"""

from __future__ import annotations

import asyncio
import json
import subprocess
from collections.abc import AsyncIterator
from pathlib import Path

import httpx
import pytest
import pytest_asyncio
from click.testing import Result
from typer.testing import CliRunner

from rosaos.cli.root import app
from rosaos.frontends.chat import EXIT_FAILED, EXIT_NOT_DONE, EXIT_OK
from rosaos.kernel.runtime import Kernel

from .cli_process import ROSAOS
from .e2e_support import (
    TWO_LIGHTS,
    all_healthy,
    device_state,
    eventually,
    kernel_api,
    running_kernel,
    scripted_kernel,
)

pytestmark = pytest.mark.asyncio(loop_scope="module")


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def home(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("chat-exit")


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(home: Path) -> AsyncIterator[Kernel]:
    async with running_kernel(home, TWO_LIGHTS) as kernel, kernel_api(kernel) as api:
        await eventually(lambda: all_healthy(api), timeout=120)
        yield kernel


@pytest.fixture(autouse=True)
def fresh_conversation(request: pytest.FixtureRequest) -> None:
    """Each case starts a conversation: an open "which one?" would take the next sentence as its answer."""
    if "kernel" in request.fixturenames:
        request.getfixturevalue("kernel").loop.reset_conversation()


async def wait_chat(kernel: Kernel, home: Path, text: str, *options: str) -> Result:
    """``rosaos chat -m TEXT --wait`` against ``kernel``, in a thread: the kernel runs on this loop."""
    args = ["chat", "-c", str(home / "rosaos.toml"), "--url", kernel.url, "-m", text, "--wait", *options]
    return await asyncio.to_thread(CliRunner().invoke, app, args)


@pytest.mark.parametrize(
    ("said", "code", "replied", "why"),
    [
        ("blorp the frobnicator", EXIT_NOT_DONE, "didn't understand", "was not understood; say it another way"),
        # A device kind the world lacks: refused, never the bedroom's nearest lamp.
        ("turn on the fan in the bedroom", EXIT_FAILED, "I have no fan", "name a device, value or place it has"),
        # An unknown colour: this engine does not understand it (it changes nothing either way).
        ("set the kitchen light to mauve", EXIT_NOT_DONE, "didn't understand", "was not understood"),
        # A room the world lacks: it asks which light, and waits for the answer.
        ("turn on the light in the garage", EXIT_NOT_DONE, "Which one do you mean", "answer it with another"),
    ],
)  # fmt: skip
async def test_nothing_done_exits_non_zero_with_what_would_work(
    kernel: Kernel, home: Path, said: str, code: int, replied: str, why: str
) -> None:
    result = await wait_chat(kernel, home, said)
    assert result.exit_code == code, result.output
    assert replied in result.stdout
    [line] = result.stderr.splitlines()
    assert line.startswith("rosaos chat: nothing was done") and why in line
    assert not (await device_state(kernel, "kitchen_light"))["on"]


async def test_did_you_mean_waits_for_a_yes_and_the_yes_runs_it(kernel: Kernel, home: Path) -> None:
    asked = await wait_chat(kernel, home, "switch kitchen light")
    assert asked.exit_code == EXIT_NOT_DONE, asked.output
    assert "Did you mean: switch on kitchen light?" in asked.stdout
    assert "`rosaos chat -m yes --wait` to run it" in asked.stderr
    assert not (await device_state(kernel, "kitchen_light"))["on"]
    confirmed = await wait_chat(kernel, home, "yes")
    assert confirmed.exit_code == EXIT_OK, confirmed.output
    assert confirmed.stderr == ""
    assert (await device_state(kernel, "kitchen_light"))["on"]
    turned_off = await wait_chat(kernel, home, "turn off the kitchen light")
    assert turned_off.exit_code == EXIT_OK, turned_off.output


@pytest.mark.parametrize(
    ("said", "answer"),
    [("is the living room lamp on?", "Yes"), ("what can you do?", "You can say, for example")],
)
async def test_an_answered_question_exits_0(kernel: Kernel, home: Path, said: str, answer: str) -> None:
    result = await wait_chat(kernel, home, said)
    assert result.exit_code == EXIT_OK, result.output
    assert answer in result.stdout and result.stderr == ""


async def test_json_shows_the_outcome(kernel: Kernel, home: Path) -> None:
    result = await wait_chat(kernel, home, "blorp the frobnicator", "--json")
    assert result.exit_code == EXIT_NOT_DONE
    summary = json.loads(result.stdout)
    assert (summary["ok"], summary["outcome"], summary["processes"]) == (False, "not_understood", [])
    done = json.loads((await wait_chat(kernel, home, "turn off the living room lamp", "--json")).stdout)
    assert (done["ok"], done["outcome"], [p["status"] for p in done["processes"]]) == (True, "done", ["ok"])


async def test_without_wait_a_message_is_only_queued(kernel: Kernel, home: Path) -> None:
    args = ["chat", "-c", str(home / "rosaos.toml"), "--url", kernel.url, "-m", "blorp the frobnicator"]
    result = await asyncio.to_thread(CliRunner().invoke, app, args)
    assert result.exit_code == EXIT_OK and result.stdout.startswith("sent as event ")


async def test_the_rosaos_process_exits_4_and_says_why(kernel: Kernel, home: Path) -> None:
    command = [ROSAOS, "chat", "-c", str(home / "rosaos.toml"), "--url", kernel.url, "-m", "blorp", "--wait"]
    ran = await asyncio.to_thread(subprocess.run, command, capture_output=True, text=True, timeout=120)
    assert ran.returncode == EXIT_NOT_DONE, ran.stdout + ran.stderr
    assert ran.stderr.startswith("rosaos chat: nothing was done: the message was not understood")


async def test_an_llm_kernel_whose_only_tool_call_is_refused_exits_1(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    """The scripted kernel (``kernel_scripts.py``) launches what "device: task" names."""
    home = tmp_path_factory.mktemp("chat-exit-llm")
    async with scripted_kernel(home, TWO_LIGHTS) as kernel, kernel_api(kernel) as api:
        await eventually(lambda: all_healthy(api), timeout=120)
        await _check_llm_outcomes(kernel, home, api)


async def _check_llm_outcomes(kernel: Kernel, home: Path, api: httpx.AsyncClient) -> None:
    refused = await wait_chat(kernel, home, "fan: turn on the fan", "--json")
    assert refused.exit_code == EXIT_FAILED, refused.output
    assert json.loads(refused.stdout)["outcome"] == "refused"
    assert "unknown device 'fan'" in refused.stderr
    launched = await wait_chat(kernel, home, "kitchen_light: call turn_on {}")
    assert launched.exit_code == EXIT_OK, launched.output
    # An LLM's words are never read for the outcome: a reply with no tool call is an answer.
    talked = await wait_chat(kernel, home, "hello")
    assert talked.exit_code == EXIT_OK, talked.output
    assert "I don't understand" in talked.stdout
