"""Progress of a long tool call: device ``report_progress`` → worker → pool → the process's ``progress``."""

from __future__ import annotations

import asyncio

import pytest
from fastmcp import Context, FastMCP
from processes_support import (
    KERNEL_TOKEN,
    TOKEN,
    Endings,
    KernelStandIn,
    LoopbackDevice,
    eventually,
    worker_env,
)

from rosaos.devices.serve import serve_http
from rosaos.kernel.commands import progress_text
from rosaos.models.plan import Plan, PlanStep, encode_task
from rosaos.models.select import ModelSpec
from rosaos.processes.manager import ProcessManager
from rosaos.processes.pool import WorkerPool
from rosaos.processes.progress import ProcessProgress, progress_from_line


@pytest.mark.asyncio(loop_scope="module")
async def test_a_long_call_shows_its_progress_while_it_runs(kernel: KernelStandIn) -> None:
    release = asyncio.Event()
    server = FastMCP("rover")

    @server.tool(annotations={"readOnlyHint": False, "destructiveHint": False})
    async def search(ctx: Context) -> dict[str, bool]:
        """Look around, reporting each view."""
        await ctx.report_progress(3, 8, "3 of 8 views")
        await release.wait()
        return {"found": True}

    async with serve_http(server, TOKEN) as served:
        rover = LoopbackDevice("rover", served.url, {})
        endpoints = {"rover": rover.endpoint("exclusive")}
        manager = ProcessManager(
            devices=lambda: endpoints,
            model=ModelSpec(model=None),  # the offline plan model runs the plan below
            base_prompt="You are a test process.",
            job_timeout=60,
            request_limit=10,
            callback_url=kernel.url,
            callback_token=KERNEL_TOKEN,
            pool=WorkerPool(size=1, env=worker_env()),
            on_ended=Endings().record,
            first_process_id=500,
        )
        await manager.start()
        try:
            plan = Plan(steps=[PlanStep(device="rover", tool="search")], reply="Found.")
            info = await manager.launch(encode_task("Search.", plan), ["rover"])
            progress = await eventually(lambda: manager.get(info.id).progress, what="progress")
            assert (progress.device, progress.percent, progress.message) == ("rover", 37, "3 of 8 views")
            assert manager.get(info.id).model_dump(mode="json")["progress"]["percent"] == 37
            release.set()
            await eventually(lambda: manager.get(info.id).state != "running", what="the end")
            assert manager.get(info.id).state == "ok"
        finally:
            release.set()
            await manager.stop()


def test_a_malformed_progress_line_is_ignored() -> None:
    assert progress_from_line({"event": "progress", "progress": "lots"}) is None
    assert progress_from_line({"event": "progress"}) is None


def test_ps_shows_percent_and_message() -> None:
    line = progress_from_line({"device": "turtlebot", "progress": 30, "total": 120, "message": "searching"})
    assert line is not None
    assert progress_text(line.model_dump(mode="json")) == "25% searching"
    no_total = ProcessProgress(device="d", progress=4, time=line.time)
    assert progress_text(no_total.model_dump(mode="json")) == "4"
    assert progress_text(None) == "-"
