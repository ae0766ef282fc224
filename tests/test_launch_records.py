"""A launch is recorded before its worker starts, and after a crash that record decides.

The store is left exactly as a kernel killed with SIGKILL leaves it in the worst window: process 7
was launched for event 1 (its record written, its worker told to start), but event 1 was not yet
marked handled. The next kernel must report process 7 as crashed and safe-stop its device, then
handle event 1 again *without* launching the same command a second time.
"""

from __future__ import annotations

import asyncio
from datetime import UTC, datetime
from pathlib import Path

from rosaos.events.types import UserText, UserTypedEvent
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.launch_cause import LaunchCause
from rosaos.kernel.orphans import LiveProcesses
from rosaos.kernel.runtime import EVENTS_FILE
from rosaos.processes.manager import ProcessInfo

from .e2e_support import TWO_LIGHTS, device_state, kernel_api, running_kernel


async def leave_a_launch_behind(data_dir: Path) -> int:
    """Write what a kernel killed right after launching process 7 for a queued event leaves."""
    await asyncio.to_thread(data_dir.mkdir, parents=True, exist_ok=True)
    store = await EventStore.open(data_dir / EVENTS_FILE)
    try:
        appended = await store.append(
            UserTypedEvent(
                kind="user_typed", source="chat", payload=UserText(text="toggle the kitchen light")
            )
        )
        await store.note_process_id(7)
        info = ProcessInfo(
            id=7,
            task="Toggle the kitchen light.",
            devices=["kitchen_light"],
            state="running",
            started_at=datetime.now(UTC),
        )
        await LiveProcesses(store).launched(info, LaunchCause(appended.id, 0))
    finally:
        await store.close()
    return appended.id


async def test_a_launch_recorded_before_a_crash_is_reported_and_never_launched_again(tmp_path: Path) -> None:
    event_id = await leave_a_launch_behind(tmp_path / "data")
    async with running_kernel(tmp_path, TWO_LIGHTS) as kernel, kernel_api(kernel) as api:
        for _ in range(200):
            if (await api.get(f"/events/{event_id}")).json()["handled"]:
                break
            await asyncio.sleep(0.05)
        updates = (await api.get("/updates", params={"after": 0, "limit": 1000})).json()["updates"]
        lamp = await device_state(kernel, "kitchen_light")
        ever = (await api.get("/processes", params={"all": "true"})).json()
    ended = [u for u in updates if u["kind"] == "process_ended"]
    assert [u["data"]["process_id"] for u in ended] == [7], ended
    assert (
        ended[0]["data"]["status"] == "crashed" and "kitchen_light safe-stopped" in ended[0]["data"]["error"]
    )
    assert not [u for u in updates if u["kind"] == "process_launched"], "the command was launched again"
    assert any("already launched as process 7" in u["text"] for u in updates), [u["text"] for u in updates]
    assert lamp["on"] is False, "the lamp was toggled by a second run of the command"
    assert [p["id"] for p in ever] == [7] and ever[0]["state"] == "crashed", ever
