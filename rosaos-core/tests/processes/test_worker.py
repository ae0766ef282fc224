"""The worker's job runner, in-process: process agents against real device servers on loopback.

The worker subprocess and its pipe protocol are exercised by the pool tests; here the same
``run_job`` runs in the test's event loop so each behaviour is quick to see.
"""

from __future__ import annotations

import json
from typing import Any

import pytest

from rosaos.devices.serve import serve_http
from rosaos.events.plan import Plan, PlanStep
from rosaos.models.select import ModelSpec
from rosaos.processes.worker import SESSIONS, TRUSTED_FOR, DeviceSessions, run_job

from .processes_support import (
    TOKEN,
    KernelStandIn,
    LoopbackDevice,
    build_test_device,
    make_job,
    model_spec,
    module_name,
)

pytestmark = pytest.mark.asyncio(loop_scope="module")


async def test_process_uses_its_device_and_reports_ok(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp = devices["lamp"]
    lamp.state["level"] = 0
    callback = await run_job(make_job(kernel, "sets_level", [lamp]))
    assert (callback.status, callback.output, callback.error) == ("ok", "lamp level is 42", None)
    assert lamp.state["level"] == 42
    assert (callback.model_requests, callback.tool_calls) == (2, 1)


async def test_one_device_keeps_its_tool_names(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    callback = await run_job(make_job(kernel, "reports_prompt", [devices["lamp"]]))
    assert json.loads(callback.output or "")["tools"] == ["get_state", "set_level"]


async def test_several_devices_get_tool_names_prefixed_by_instance(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    callback = await run_job(make_job(kernel, "reports_prompt", [devices["lamp"], devices["fan"]]))
    report = json.loads(callback.output or "")
    assert report["tools"] == ["fan_get_state", "fan_set_level", "lamp_get_state", "lamp_set_level"]
    assert "You are a test process." in report["system"]
    assert "## fan (testdevice)" in report["system"]


async def test_prefixed_tools_reach_the_right_devices(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    devices["lamp"].state["level"] = devices["fan"].state["level"] = 0
    callback = await run_job(make_job(kernel, "sets_level", [devices["lamp"], devices["fan"]]))
    assert callback.status == "ok"
    assert devices["lamp"].state["level"] == devices["fan"].state["level"] == 42
    assert callback.tool_calls == 2


async def test_a_failed_device_call_is_an_error_even_when_the_model_reports_it_politely(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp = devices["lamp"]
    lamp.state.update(level=0, jammed=True)
    try:
        callback = await run_job(make_job(kernel, "sets_level", [lamp]))
    finally:
        lamp.state.pop("jammed")
    # The scripted model answers with the tool's (failed) result as if all were well.
    assert "jammed" in (callback.output or "")
    assert callback.status == "error"
    assert callback.error == "lamp: set_level failed: lamp is jammed; free it and try again"
    assert lamp.state["level"] == 0


async def test_a_model_that_says_done_without_a_device_call_does_not_end_ok(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp = devices["lamp"]
    lamp.state["level"] = 0
    callback = await run_job(make_job(kernel, "claims_done", [lamp]))
    assert callback.status == "unverified"
    assert callback.output == "Done, it is on."  # kept, but not taken for a result
    assert "no successful device call" in (callback.error or "")
    assert lamp.state["level"] == 0


async def test_a_change_task_whose_calls_only_read_does_not_end_ok(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp = devices["lamp"]
    lamp.state["level"] = 0
    job = make_job(kernel, "only_reads", [lamp]).model_copy(update={"task": "Set the lamp to 42 %."})
    callback = await run_job(job)
    assert callback.status == "unverified"
    assert "only read state (lamp.get_state)" in (callback.error or "")
    assert lamp.state["level"] == 0


async def test_a_question_answered_by_reading_ends_ok(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    job = make_job(kernel, "only_reads", [devices["lamp"]]).model_copy(
        update={"task": "What level is the lamp at?"}
    )
    callback = await run_job(job)
    assert (callback.status, callback.error) == ("ok", None)


async def test_a_call_to_a_device_not_granted_is_logged_and_named_by_the_missing_lease(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp = devices["lamp"]
    lamp.state["level"] = 0
    job = make_job(kernel, "calls_unleased", [lamp]).model_copy(update={"world_devices": ["fan", "lamp"]})
    callback = await run_job(job)
    refused, done = callback.receipts
    assert (refused.device, refused.tool, refused.ok) == ("fan", "fan_set_level", False)
    assert refused.error is not None
    assert refused.error.startswith(f"process {job.process_id} holds no lease on fan; it holds lamp")
    # The model read the same words, not pydantic-ai's list of every tool name.
    answers = json.loads(callback.output or "")
    assert f"process {job.process_id} holds no lease on fan" in answers[0], answers
    assert "Available tools" not in answers[0]
    # It corrected itself with a tool it holds: judged on its real calls.
    assert (done.tool, done.ok, callback.status) == ("set_level", True, "ok")
    assert lamp.state["level"] == 42


async def test_a_report_written_beside_the_finishing_call_ends_the_process_in_one_request(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp = devices["lamp"]
    lamp.state["level"] = 0
    callback = await run_job(make_job(kernel, "reports_beside_call", [lamp]))
    assert (callback.status, callback.output, callback.model_requests) == ("ok", "The level is 42.", 1)
    assert lamp.state["level"] == 42


async def test_a_report_written_beside_a_call_that_failed_is_not_taken(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp = devices["lamp"]
    lamp.state.update(level=0, jammed=True)
    try:
        callback = await run_job(make_job(kernel, "reports_beside_call", [lamp]))
    finally:
        lamp.state.pop("jammed")
    assert (callback.output, callback.model_requests, callback.status) == ("asked again", 2, "error")


async def test_a_device_granted_with_a_tool_list_offers_only_those_tools(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    job = make_job(kernel, "reports_prompt", [devices["lamp"]])
    job.devices[0].tools = ["get_state"]
    callback = await run_job(job)
    assert json.loads(callback.output or "")["tools"] == ["get_state"]


async def test_unreachable_device_is_an_error_naming_it(kernel: KernelStandIn, unreachable_url: str) -> None:
    dead = LoopbackDevice("dead_lamp", unreachable_url.replace("/event", "/mcp"), {})
    callback = await run_job(make_job(kernel, "sets_level", [dead]))
    assert callback.status == "error"
    assert (callback.error or "").startswith(f"cannot reach device dead_lamp at {dead.url}")
    assert "Traceback" not in (callback.error or "")


async def test_device_that_refuses_the_token_is_an_error_saying_so(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    job = make_job(kernel, "sets_level", [devices["lamp"]])
    job.devices[0] = job.devices[0].model_copy(update={"token": "wrong"})
    callback = await run_job(job)
    assert callback.status == "error"
    assert f"device lamp at {devices['lamp'].url} refused the bearer token (HTTP 401)" in (
        callback.error or ""
    )


async def test_request_limit_ends_the_process_with_a_clear_error(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    callback = await run_job(make_job(kernel, "polls_forever", [devices["lamp"]], request_limit=3))
    assert callback.status == "error"
    assert "limit of 3 model requests" in (callback.error or "")
    assert callback.model_requests == 3


async def test_model_failure_is_an_error_with_one_readable_line(kernel: KernelStandIn) -> None:
    callback = await run_job(make_job(kernel, "fails"))
    assert (callback.status, callback.error) == ("error", "RuntimeError: the model exploded")


async def test_job_past_its_timeout_is_stopped_by_the_worker(kernel: KernelStandIn) -> None:
    callback = await run_job(make_job(kernel, "sleeps", timeout=0.3))
    assert callback.status == "timeout"
    assert "timeout of 0.3 s" in (callback.error or "")


async def test_with_no_model_a_task_without_a_plan_says_how_to_configure_one(kernel: KernelStandIn) -> None:
    job = make_job(kernel, "unused").model_copy(update={"model": ModelSpec()})
    callback = await run_job(job)
    assert callback.status == "ok"
    assert (callback.output or "").startswith("The offline engine only runs planned tasks")


async def test_model_that_cannot_be_imported_is_an_error(kernel: KernelStandIn) -> None:
    job = make_job(kernel, "unused").model_copy(update={"model": model_spec("no_such_factory")})
    callback = await run_job(job)
    assert callback.status == "error"
    assert (callback.error or "").startswith(
        f"cannot import model '{module_name('process_test_models')}:no_such_factory'"
    )


async def test_a_warm_worker_keeps_its_device_session_for_the_next_job(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp = devices["lamp"]
    assert (await run_job(make_job(kernel, "sets_level", [lamp]))).status == "ok"
    first = SESSIONS._open[(lamp.url, TOKEN)]
    assert (await run_job(make_job(kernel, "sets_level", [lamp]))).status == "ok"
    assert SESSIONS._open[(lamp.url, TOKEN)] is first


async def test_a_device_restarted_at_the_same_url_gets_a_fresh_session(kernel: KernelStandIn) -> None:
    state: dict[str, Any] = {"level": 0}
    async with serve_http(build_test_device("heater", state), TOKEN) as served:
        heater = LoopbackDevice("heater", served.url, state)
        port = int(served.url.rsplit(":", 1)[1].split("/")[0])
        assert (await run_job(make_job(kernel, "sets_level", [heater]))).status == "ok"
    state["level"] = 0
    async with serve_http(build_test_device("heater", state), TOKEN, port=port):
        callback = await run_job(make_job(kernel, "sets_level", [heater]))
    assert (callback.status, state["level"]) == ("ok", 42)


def with_epoch(job: Any, epoch: str | None) -> Any:
    devices = [device.model_copy(update={"server_epoch": epoch}) for device in job.devices]
    return job.model_copy(update={"devices": devices})


async def test_a_kept_session_of_the_same_server_is_trusted_for_a_while_without_a_check(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    now = [0.0]
    sessions = DeviceSessions(clock=lambda: now[0])
    lamp = with_epoch(make_job(kernel, "sets_level", [devices["lamp"]]), "pid-7").devices[0]
    opened = await sessions.toolset(lamp)
    checks: list[str] = []
    list_tools = opened.client.list_tools

    async def counted() -> Any:
        checks.append("tools/list")
        return await list_tools()

    opened.client.list_tools = counted  # type: ignore[method-assign]
    try:
        now[0] = TRUSTED_FOR / 2
        assert await sessions.toolset(lamp) is opened
        assert checks == []  # same server, used lately: no round trip before the job
        now[0] += TRUSTED_FOR
        assert await sessions.toolset(lamp) is opened
        assert checks == ["tools/list"]  # idle too long: the server may have ended it
        assert await sessions.toolset(lamp.model_copy(update={"server_epoch": None})) is opened
        assert checks == ["tools/list"] * 2  # a server the kernel cannot name: always checked
    finally:
        await sessions.close_all()


async def test_a_device_restarted_under_a_new_server_epoch_gets_a_fresh_session(
    kernel: KernelStandIn,
) -> None:
    state: dict[str, Any] = {"level": 0}
    async with serve_http(build_test_device("heater", state), TOKEN) as served:
        heater = LoopbackDevice("heater", served.url, state)
        port = int(served.url.rsplit(":", 1)[1].split("/")[0])
        first = await run_job(with_epoch(make_job(kernel, "sets_level", [heater]), "pid-1"))
        assert first.status == "ok"
    state["level"] = 0
    async with serve_http(build_test_device("heater", state), TOKEN, port=port):
        callback = await run_job(with_epoch(make_job(kernel, "sets_level", [heater]), "pid-2"))
    assert (callback.status, state["level"]) == ("ok", 42)


# Planned tasks run without an agent (processes/plan_runner.py)


def planned_job(
    kernel: KernelStandIn, devices: list[LoopbackDevice], *steps: tuple[str, str, dict[str, Any]]
) -> Any:
    plan = Plan(
        steps=[PlanStep(device=device, tool=tool, args=args) for device, tool, args in steps],
        reply="Done: {result}",
        failure="Sorry, that failed: {error}",
    )
    job = make_job(kernel, "unused", devices)
    return job.model_copy(update={"model": ModelSpec(), "task": "Set the levels.", "plan": plan})


async def test_a_planned_task_calls_its_tools_directly_with_receipts(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp, fan = devices["lamp"], devices["fan"]
    lamp.state["level"] = fan.state["level"] = 0
    # 250 is out of range: clamped to the schema's maximum, as the plan model always did.
    job = planned_job(
        kernel, [lamp, fan], ("lamp", "set_level", {"level": 250}), ("fan", "set_level", {"level": 7})
    )
    callback = await run_job(job)
    assert (callback.status, callback.output) == ("ok", "Done: fan level is 7")
    assert (lamp.state["level"], fan.state["level"]) == (100, 7)
    assert (callback.model_requests, callback.tool_calls) == (0, 2)
    assert [(r.device, r.tool, r.arguments, r.ok) for r in callback.receipts] == [
        ("lamp", "set_level", {"level": 100}, True),
        ("fan", "set_level", {"level": 7}, True),
    ]


async def test_a_planned_step_that_fails_stops_the_plan_with_the_device_error(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp, fan = devices["lamp"], devices["fan"]
    lamp.state.update(level=0, jammed=True)
    fan.state["level"] = 0
    try:
        job = planned_job(
            kernel, [lamp, fan], ("lamp", "set_level", {"level": 5}), ("fan", "set_level", {"level": 9})
        )
        callback = await run_job(job)
    finally:
        lamp.state.pop("jammed")
    assert callback.output == "Sorry, that failed: lamp is jammed; free it and try again"
    assert callback.status == "error"
    assert fan.state["level"] == 0  # the plan stopped at the failed step


async def test_a_planned_step_naming_a_missing_tool_says_which_tools_exist(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    callback = await run_job(planned_job(kernel, [devices["lamp"]], ("lamp", "explode", {})))
    assert (callback.output or "").startswith("Sorry, that failed:")
    assert "get_state" in (callback.output or "") and "set_level" in (callback.output or "")
