"""The activity log: receipts from worker callbacks, stored once, read back through the API and CLI."""

from __future__ import annotations

import json
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import httpx
import pytest
from fastapi import FastAPI

from rosaos.cli.log_command import log_command, parse_since
from rosaos.events.callback import WorkerCallback
from rosaos.events.types import Event, WorkerCallbackEvent
from rosaos.kernel.activity import ActivityLog
from rosaos.kernel.api.app import create_app
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.intake import Queued
from rosaos.kernel.loop import render_event
from rosaos.kernel.process_ends import end_event
from rosaos.kernel.updates import UpdateStream
from rosaos.receipts import Receipt, SafetyDecision

from .kernel_support import AUTH, TOKEN, TestRuntime, kitchen_light


def receipt(tool: str, started: float, device: str = "turtlebot", **fields: Any) -> Receipt:
    return Receipt(device=device, tool=tool, ok=True, result="{}", started=started, duration=0.5, **fields)


@pytest.fixture
async def activity_runtime(store: EventStore, updates: UpdateStream) -> TestRuntime:
    """The test runtime, keeping receipts in a real activity log as the kernel's process ends do."""
    runtime = TestRuntime(events=store, updates=updates, device_list=[kitchen_light()])
    activity = runtime.activity = await ActivityLog.open(store.database)

    async def record(queued: Queued) -> None:
        assert isinstance(queued.event.payload, WorkerCallback)
        await activity.record(queued.id, queued.event.payload.process_id, queued.event.payload.receipts)

    runtime.intake.on("worker_callback", record)
    return runtime


@pytest.fixture
async def activity_client(activity_runtime: TestRuntime) -> Any:
    app: FastAPI = create_app(activity_runtime)
    async with httpx.AsyncClient(
        transport=httpx.ASGITransport(app=app), base_url="http://127.0.0.1:8765"
    ) as http:
        yield http


def process_end(process_id: int, receipts: list[Receipt]) -> WorkerCallbackEvent:
    """A process's end as the pool reports it, with the tool calls the process made."""
    return end_event(WorkerCallback(process_id=process_id, status="ok", output="done", receipts=receipts))


async def test_receipts_of_a_callback_are_logged_once_and_filtered(
    activity_client: httpx.AsyncClient, activity_runtime: TestRuntime
) -> None:
    now = time.time()
    drove = receipt("drive", now - 60, arguments={"linear": 0.2}, safety=SafetyDecision(decision="clamped"))
    lamp = receipt("set_brightness", now - 30, device="kitchen_light")
    for _ in range(2):  # an end reported twice (the pool, then orphan recovery) is not logged twice
        await activity_runtime.intake.submit(process_end(5, [drove, lamp]))
    await activity_runtime.intake.submit(process_end(6, [receipt("rotate", now)]))

    every = (await activity_client.get("/activity", headers=AUTH)).json()["entries"]
    assert [(e["process_id"], e["tool"]) for e in every] == [
        (5, "drive"),
        (5, "set_brightness"),
        (6, "rotate"),
    ]
    assert every[0]["arguments"] == {"linear": 0.2} and every[0]["safety"]["decision"] == "clamped"
    by_device = (await activity_client.get("/activity", params={"device": "turtlebot"}, headers=AUTH)).json()
    assert [e["tool"] for e in by_device["entries"]] == ["drive", "rotate"]
    by_process = (await activity_client.get("/activity", params={"process": 6}, headers=AUTH)).json()
    assert [e["tool"] for e in by_process["entries"]] == ["rotate"]
    recent = (await activity_client.get("/activity", params={"since": now - 45}, headers=AUTH)).json()
    assert [e["tool"] for e in recent["entries"]] == ["set_brightness", "rotate"]
    newest = (await activity_client.get("/activity", params={"limit": 1}, headers=AUTH)).json()
    assert [e["tool"] for e in newest["entries"]] == ["rotate"]


async def test_activity_needs_the_token_and_valid_filters(activity_client: httpx.AsyncClient) -> None:
    assert (await activity_client.get("/activity")).status_code == 401
    bad = await activity_client.get("/activity", params={"process": 0}, headers=AUTH)
    assert bad.status_code == 422 and "process" in bad.text


def test_the_kernel_model_sees_the_receipts_and_the_engine_still_reads_the_output() -> None:
    refused = Receipt(
        device="turtlebot",
        tool="drive",
        arguments={"linear": 0.8},
        ok=False,
        error="refused: 0.8 m/s is above the velocity limit",
        started=1.0,
        duration=0.01,
        safety=SafetyDecision(decision="refused", rule="velocity limit"),
    )
    callback = WorkerCallback(process_id=7, status="ok", output="I could not drive", receipts=[refused])
    text = render_event(
        Event(id=1, time=datetime.now(UTC), kind="worker_callback", source="t", payload=callback)
    )
    assert text.splitlines()[1:] == [
        'output: "I could not drive"',
        "tool calls:",
        '- turtlebot.drive(linear=0.8) -> error: "refused: 0.8 m/s is above the velocity limit"',
    ]


def test_since_takes_durations_and_iso_times() -> None:
    assert parse_since("10m", now=1000.0) == 400.0
    assert parse_since("2h", now=10_000.0) == 2800.0
    assert parse_since("2026-05-01T14:00:00+00:00") == datetime(2026, 5, 1, 14, tzinfo=UTC).timestamp()
    with pytest.raises(ValueError, match="30s, 10m, 2h, 1d"):
        parse_since("yesterday")


async def test_rosaos_log_json_reads_the_served_api(
    served: str,
    runtime: TestRuntime,
    store: EventStore,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    runtime.activity = await ActivityLog.open(store.database)  # type: ignore[attr-defined]
    await runtime.activity.record(1, 3, [receipt("drive", time.time(), arguments={"linear": 0.1})])  # type: ignore[attr-defined]
    monkeypatch.setenv("ROSAOS_DATA_DIR", str(tmp_path))
    (tmp_path / "token").write_text(TOKEN)
    import asyncio

    code = await asyncio.to_thread(log_command, None, served, "turtlebot", None, "1h", 50, True)
    entries = json.loads(capsys.readouterr().out)
    assert code == 0 and [(e["process_id"], e["tool"], e["arguments"]) for e in entries] == [
        (3, "drive", {"linear": 0.1})
    ]


async def test_rosaos_log_reads_the_store_when_no_kernel_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    store = await EventStore.open(tmp_path / "kernel.sqlite3")
    log = await ActivityLog.open(store.database)
    await log.record(9, 4, [receipt("rotate", time.time(), arguments={"degrees": 90})])
    await store.close()
    monkeypatch.setenv("ROSAOS_DATA_DIR", str(tmp_path))
    import asyncio

    code = await asyncio.to_thread(log_command, None, None, None, 4, None, 10, True)
    entries = json.loads(capsys.readouterr().out)
    assert code == 0 and [(e["process_id"], e["tool"]) for e in entries] == [(4, "rotate")]
