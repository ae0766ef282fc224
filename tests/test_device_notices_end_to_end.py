"""Device notices through the real kernel: a driver's ``ctx.notify`` → ``GET /notices`` → the kernel's
watcher → a ``[Device notice]`` event → the offline engine's answer, with repeats dropped.

The Tapo simulator is served in this process (the benchmark's ``SimDevices``), so the test can
post on its notice board exactly as the driver's backend would. Without a Reachy Mini in the world
the engine says a ``notify`` notice as a chat reply; an ``info`` notice gets none.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
import pytest_asyncio

from rosaos.bench.sim_world import SimDevices
from rosaos.config import load_config
from rosaos.devices import serve
from rosaos.devices.world import build_world
from rosaos.kernel.runtime import Kernel
from rosaos.notices.notice_board import NoticeBoard
from rosaos.plugins import load_drivers

from .e2e_support import eventually

pytestmark = pytest.mark.asyncio(loop_scope="module")

WORLD = """
[devices.lamp]
driver = "tapo"
description = "Lamp on the desk"
"""


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[Kernel]:
    home: Path = tmp_path_factory.mktemp("notices")
    (home / "rosaos.toml").write_text(f'data_dir = "{home / "data"}"\n' + WORLD)
    config = load_config(home / "rosaos.toml")
    world = build_world(config, load_drivers())
    kernel = Kernel(config, world, devices=SimDevices(world, config.data_dir))
    await kernel.start(port=0)
    try:
        yield kernel
    finally:
        await kernel.stop()


def lamp_board() -> NoticeBoard:
    # The board of the served lamp, as its driver's ctx.notices (registered when its route was added).
    [board] = [b for b in serve._BOARDS.values() if b.instance == "lamp"]
    board.specs = None  # accept any name: this tests the transport, not the Tapo declaration
    return board


async def updates(kernel: Kernel) -> list[Any]:
    return list(await kernel.updates.after(0, 1000))


async def test_a_notify_notice_reaches_the_user_once(kernel: Kernel) -> None:
    board = lamp_board()
    board.post("unreachable", {"since": 3}, message="The lamp stopped answering.", importance="notify")
    board.post("unreachable", {"since": 3}, message="The lamp stopped answering.", importance="notify")

    async def replied() -> list[str]:
        return [
            u.text
            for u in await updates(kernel)
            if u.kind == "kernel_reply" and "stopped answering" in u.text
        ]

    assert await eventually(replied) == ["The lamp stopped answering."]
    events = [u for u in await updates(kernel) if u.kind == "event" and u.data.get("kind") == "device_notice"]
    assert len(events) == 1  # the repeat was dropped before the queue
    payload = events[0].data["payload"]
    assert (payload["device"], payload["name"], payload["driver"], payload["importance"]) == (
        "lamp",
        "unreachable",
        "tapo",
        "notify",
    )


async def test_an_info_notice_is_queued_and_answered_with_silence(kernel: Kernel) -> None:
    board = lamp_board()
    board.post("reachable", message="The lamp answers again.", importance="info")

    async def queued_and_handled() -> bool:
        seen = any(
            u.kind == "event" and u.data.get("payload", {}).get("name") == "reachable"
            for u in await updates(kernel)
        )
        return seen and await kernel.events.pending_count() == 0

    await eventually(queued_and_handled)
    assert not [u for u in await updates(kernel) if u.kind == "kernel_reply" and "answers again" in u.text]
