"""A spoken "turtlebot" reaches the turtlebot (issue 25, "heard right").

Moonshine alone hears espeak-ng's "turtlebot" as "turtle not" or "total not", and the command then
names no device. ``rosaos voice`` biases the decoder toward the world's words (the device names in
rosaos.toml), so "hello. drive the turtlebot forward one meter" is heard as said, the offline
engine plans it, and the TurtleBot 4 simulator drives forward. Real parts: the voice CLI in its own process, the kernel
and its worker, the ROS driver's simulator over MCP HTTP.
"""

from __future__ import annotations

import shutil
import subprocess
from collections.abc import AsyncIterator
from pathlib import Path

import pytest
import pytest_asyncio

from rosaos.frontends.voice.end_of_turn import KernelJudge
from rosaos.kernel.api.kernel_client import KernelClient
from rosaos.kernel.runtime import Kernel

from .e2e_support import device_state, eventually, kernel_api, running_kernel
from .voice_e2e_support import rosaos_voice

pytestmark = [
    pytest.mark.asyncio(loop_scope="module"),
    pytest.mark.skipif(
        shutil.which("espeak-ng") is None, reason="espeak-ng is not installed: apt-get install espeak-ng"
    ),
]
WORLD = """
[devices.turtlebot]
driver = "ros"
profile = "turtlebot4"
description = "TurtleBot4 wheeled mobile robot with a camera and a charging dock"
sim = { docked = false }

[devices.kitchen_light]
driver = "tapo"
description = "Ceiling light in the kitchen"
"""


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[Kernel]:
    async with running_kernel(tmp_path_factory.mktemp("voice-turtlebot"), WORLD) as kernel:
        yield kernel


@pytest.fixture
def wav(tmp_path: Path) -> Path:
    path = tmp_path / "forward.wav"
    subprocess.run(["espeak-ng", "-w", str(path), "hello. drive the turtlebot forward one meter"], check=True)
    return path


async def test_spoken_turtlebot_command_reaches_the_turtlebot(kernel: Kernel, wav: Path) -> None:
    start = (await device_state(kernel, "turtlebot"))["x"]

    # The drive and the reply it waits for take a while on a loaded machine.
    code, heard, stderr = await rosaos_voice(kernel, wav, timeout=400)

    assert code == 0, stderr
    sent = [h["text"] for h in heard if h["kind"] == "sent"]
    transcripts = [h["text"] for h in heard if h["kind"] == "transcript"]
    assert len(sent) == 1, f"heard {transcripts}; {stderr}"
    assert "turtlebot" in sent[0].lower()

    async def moved() -> bool:
        return bool((await device_state(kernel, "turtlebot"))["x"] > start + 0.5)

    await eventually(moved, timeout=120)


async def test_the_turn_judge_hears_that_a_command_would_move_a_robot(kernel: Kernel) -> None:
    """``POST /understand`` says ``moves`` for a whole command that sets a robot moving, so the voice
    front end never ends such a turn early; a light switch and a stop do not move anything."""
    async with kernel_api(kernel) as api:

        async def judge(text: str) -> dict[str, object]:
            answer: dict[str, object] = (await api.post("/understand", json={"text": text})).json()
            return answer

        drive = await judge("drive the turtlebot forward")
        light = await judge("turn on the kitchen light")
        stop = await judge("stop the turtlebot")
    assert drive["complete"] is True and drive["moves"] is True
    assert light["complete"] is True and light["moves"] is False
    assert stop["moves"] is False
    # The voice front end's judge: a whole command ends the turn early, a motion never does.
    async with KernelClient.from_config(kernel.config, url=kernel.url) as client:
        judge = KernelJudge(client)
        assert await judge.complete("turn on the kitchen light") is True
        assert await judge.complete("drive the turtlebot forward") is False
