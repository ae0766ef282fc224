"""Receipts: the worker records every tool call of a process, redacted, with its safety decision."""

from __future__ import annotations

from typing import Annotated, Any

import pytest
from fastmcp import FastMCP
from pydantic import Field

from rosaos.devices.serve import serve_http
from rosaos.drivers import DeviceError
from rosaos.models.select import ModelSpec
from rosaos.processes.worker import run_job
from rosaos.receipts import REDACTED, safety_report, secret_args_meta

from .processes_support import TOKEN, KernelStandIn, LoopbackDevice, make_job, module_name

pytestmark = pytest.mark.asyncio(loop_scope="module")


def build_guarded_device() -> FastMCP:
    """A device whose tools take a secret, refuse a speed, and clamp a nudge."""
    server = FastMCP("door")

    @server.tool(meta=secret_args_meta("pin"), annotations={"readOnlyHint": False})
    def set_pin(pin: str, label: str) -> dict[str, Any]:
        """Set the door's PIN."""
        return {"label": label, "set": True}

    @server.tool(annotations={"readOnlyHint": False, "destructiveHint": True})
    def move(speed: Annotated[float, Field(ge=0, le=5)]) -> dict[str, Any]:
        """Move the door."""
        raise DeviceError(f"refused: {speed:g} m/s is above the velocity limit of 0.3 m/s")

    @server.tool(annotations={"readOnlyHint": False})
    def nudge() -> dict[str, Any]:
        """Nudge the door a little."""
        return {"moved": 0.1, **safety_report("clamped", "max step", "asked 0.5 m, moved 0.1 m")}

    return server


async def test_every_call_gets_a_receipt_with_secrets_redacted(kernel: KernelStandIn) -> None:
    async with serve_http(build_guarded_device(), TOKEN) as served:
        door = LoopbackDevice("door", served.url, {})
        job = make_job(kernel, "calls_each_scripted_tool", [door])
        model = ModelSpec(model=f"python:{module_name('receipts_test_models')}:calls_each_scripted_tool")
        callback = await run_job(job.model_copy(update={"model": model}))
    # The refused move was never made good: the process fails (processes/tool_calls.py), and its
    # receipts still say what each call did.
    assert callback.status == "error" and "velocity limit" in (callback.error or "")
    set_pin, move, nudge = callback.receipts
    assert (set_pin.device, set_pin.tool, set_pin.ok) == ("door", "set_pin", True)
    assert set_pin.arguments == {"pin": REDACTED, "label": "front door"}
    assert "1234" not in callback.model_dump_json()
    assert set_pin.result is not None and '"set": true' in set_pin.result
    assert set_pin.started > 0 and set_pin.duration >= 0
    assert move.ok is False and move.error is not None and "velocity limit" in move.error
    assert move.safety is not None and (move.safety.decision, move.safety.rule) == (
        "refused",
        "velocity limit",
    )
    assert nudge.ok and nudge.safety is not None and nudge.safety.decision == "clamped"
    assert nudge.safety.detail == "asked 0.5 m, moved 0.1 m"
