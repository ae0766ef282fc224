"""Every confirmation is a safety decision in the activity log (``rosaos log``): asked, yes, no, expired.

The desk, the activity log and the update stream are the kernel's own, on a SQLite file in ``tmp_path``.
"""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from rosaos.confirmations.confirmation_chat import record_confirmation
from rosaos.confirmations.confirmation_desk import ConfirmationDesk, ConfirmationRequest
from rosaos.kernel.activity import ActivityLog
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.updates import UpdateStream

pytestmark = pytest.mark.asyncio


async def logged(
    tmp_path: Path, timeout: float
) -> tuple[ConfirmationDesk, ActivityLog, UpdateStream, EventStore]:
    store = await EventStore.open(tmp_path / "kernel.sqlite3")
    activity = await ActivityLog.open(store.database)
    updates = await UpdateStream.open(store.database)
    desk = ConfirmationDesk(timeout, record=lambda item: record_confirmation(activity, updates, item))
    return desk, activity, updates, store


async def decisions(activity: ActivityLog) -> list[tuple[str, str, bool]]:
    for _ in range(100):  # the settled record is written in a task of its own
        entries = await activity.query(limit=10)
        if len(entries) >= 2:
            break
        await asyncio.sleep(0.02)
    return [(e.tool, e.safety.decision if e.safety else "", e.ok) for e in entries]


async def test_a_question_nobody_answers_is_logged_as_asked_then_expired_and_told(tmp_path: Path) -> None:
    desk, activity, updates, store = await logged(tmp_path, timeout=0.1)
    try:
        item = await desk.ask(
            ConfirmationRequest(process_id=3, device="turtlebot", tool="drive", arguments={})
        )
        await desk.wait(item.id, 2.0)
        assert await decisions(activity) == [("drive", "confirm_asked", True), ("drive", "expired", False)]
        notices = [u.text for u in await updates.after(0) if u.kind == "notice"]
        assert notices == [f"confirm {item.id} expired: nobody answered, so it was not done: {item.question}"]
    finally:
        await store.close()


@pytest.mark.parametrize(("answer", "decision"), [("yes", "confirmed"), ("no", "declined")])
async def test_an_answer_is_logged_with_who_gave_it(tmp_path: Path, answer: str, decision: str) -> None:
    desk, activity, updates, store = await logged(tmp_path, timeout=30)
    try:
        item = await desk.ask(ConfirmationRequest(process_id=3, device="turtlebot", tool="set_param"))
        desk.answer(item.id, answer, by="web")  # type: ignore[arg-type]
        logged_decisions = await decisions(activity)
        assert logged_decisions == [
            ("set_param", "confirm_asked", True),
            ("set_param", decision, answer == "yes"),
        ]
        entries = await activity.query(limit=10)
        assert entries[-1].safety is not None and "by web" in entries[-1].safety.detail
        assert not [u for u in await updates.after(0) if u.kind == "notice"]  # only an expiry is a notice
    finally:
        await store.close()
