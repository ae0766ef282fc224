"""A follow-up rides on its process's callback event, so a kernel that never saw the launch runs it.

The offline engine's plan for "turn on the desk lamp, then turn on the shelf lamp" carries the
second step in the first process's task. Here a fresh kernel (as after a restart) receives only
that process's ``worker_callback`` (queued as the pool, or orphan recovery, queues it) and launches
the follow-up on the real Tapo simulator; a failed callback launches nothing.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from typing import Any

import pytest
import pytest_asyncio

from rosaos.intents.grammar.vocabulary import device_vocabularies
from rosaos.intents.planning.follow_ups import plan_follow_up
from rosaos.kernel.process_ends import end_event
from rosaos.kernel.runtime import Kernel
from rosaos.models.kernel_model import LocalIntentModel
from rosaos.processes.jobs import WorkerCallback

from .e2e_support import device_state, eventually, running_kernel

pytestmark = pytest.mark.asyncio(loop_scope="module")

WORLD = """
[devices.desk_lamp]
driver = "tapo"
description = "Lamp on the desk"
sim = { on = false }

[devices.shelf_lamp]
driver = "tapo"
description = "Lamp on the shelf"
sim = { on = false }
"""


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def kernel(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[Kernel]:
    async with running_kernel(tmp_path_factory.mktemp("durable"), WORLD) as kernel:
        yield kernel


def first_launch(kernel: Kernel) -> dict[str, Any]:
    """The first process's task and plan (the plan carries the follow-up), as the engine launches it."""
    model = LocalIntentModel(device_vocabularies(kernel.world))
    result = plan_follow_up("Turn on the desk lamp, then turn on the shelf lamp", model.match)
    assert result is not None
    args = result.processes[0].launch_args
    return {"task": args["task"], "plan": args["plan"]}


async def post_callback(kernel: Kernel, process_id: int, **fields: Any) -> None:
    callback = WorkerCallback(process_id=process_id, **first_launch(kernel), **fields)
    assert not (await kernel.intake.submit(end_event(callback))).duplicate


async def test_a_failed_callback_from_before_the_restart_launches_nothing(kernel: Kernel) -> None:
    await post_callback(kernel, 9001, status="crashed", error="kernel restarted: desk_lamp safe-stopped")
    await eventually(lambda: _handled(kernel))
    assert (await device_state(kernel, "shelf_lamp"))["on"] is False
    assert await kernel.processes(include_ended=True) == []


async def test_a_successful_callback_from_before_the_restart_launches_the_follow_up(kernel: Kernel) -> None:
    await post_callback(kernel, 9002, status="ok", output="Done: turn on the desk lamp.")

    async def shelf_on() -> bool:
        return bool((await device_state(kernel, "shelf_lamp"))["on"])

    await eventually(shelf_on)
    [process] = await kernel.processes(include_ended=True)
    assert process.devices == ["shelf_lamp"]
    assert (await device_state(kernel, "desk_lamp"))["on"] is False  # only the follow-up ran


async def _handled(kernel: Kernel) -> bool:
    return await kernel.events.pending_count() == 0
