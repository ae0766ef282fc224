"""A device tool's MCP progress reaches the process manager through the worker (``rosaos ps``)."""

from __future__ import annotations

import asyncio

import pytest
from fastmcp import Context, FastMCP

from rosaos.cli.process_commands import progress_text
from rosaos.devices.serve import serve_http
from rosaos.processes.manager import ProcessManager
from rosaos.processes.pool import WorkerPool

from .processes_support import (
    KERNEL_TOKEN,
    TOKEN,
    Endings,
    KernelStandIn,
    LoopbackDevice,
    eventually,
    model_spec,
    worker_env,
)

pytestmark = pytest.mark.slow


def ramp_device() -> FastMCP:
    """A device whose one tool is a long task: ten steps, a progress notification after each."""
    server = FastMCP("winch")

    @server.tool(annotations={"readOnlyHint": False, "destructiveHint": False, "idempotentHint": False})
    async def ramp(ctx: Context) -> str:
        """Wind the winch in ten steps, reporting progress."""
        for step in range(1, 11):
            await ctx.report_progress(progress=step, total=10, message=f"wound {step} of 10 turns")
            await asyncio.sleep(0.4)
        return "wound 10 turns"

    return server


async def test_progress_of_a_long_tool_shows_on_the_running_process(kernel: KernelStandIn) -> None:
    async with serve_http(ramp_device(), TOKEN) as served:
        winch = LoopbackDevice("winch", served.url, {})
        endpoints = {"winch": winch.endpoint("exclusive")}
        endings = Endings()
        manager = ProcessManager(
            devices=lambda: endpoints,
            model=model_spec("by_task"),
            base_prompt="You are a test process.",
            job_timeout=60,
            request_limit=10,
            kernel_url=kernel.url,
            kernel_token=KERNEL_TOKEN,
            pool=WorkerPool(size=1, env=worker_env()),
            on_ended=endings.record,
            first_process_id=900_000,
        )
        await manager.start()
        try:
            info = await manager.launch("ramp the winch", ["winch"])
            progress = await eventually(
                lambda: manager.get(info.id).progress, within=60, what="progress on the process"
            )
            assert progress.device == "winch" and progress.total == 10
            assert progress.message.startswith("wound ") and progress.message.endswith(" of 10 turns")
            callback = await endings.wait(info.id)
            assert callback.status == "ok" and "wound 10 turns" in (callback.output or "")
            assert manager.get(info.id).progress is not None  # the last one stays on the record
        finally:
            await manager.stop()


def test_ps_shows_percent_and_message() -> None:
    line = {"device": "turtlebot", "progress": 30.0, "total": 120.0, "message": "looked 3 of 8 ways"}
    assert progress_text(line) == "25% looked 3 of 8 ways"
    assert progress_text({"device": "d", "progress": 3, "total": None, "message": "feedback"}) == "feedback"
    assert progress_text(None) == ""
