"""The event store: committed before the id is returned, idempotent, delivered at least once, in order."""

from __future__ import annotations

import asyncio
import sqlite3
from pathlib import Path

import pytest
from pydantic import ValidationError

from rosaos.events.callback import WorkerCallback
from rosaos.events.types import (
    NEW_EVENT,
    DeviceNotice,
    DeviceNoticeEvent,
    UserText,
    UserTypedEvent,
    WorkerCallbackEvent,
)
from rosaos.kernel.database import StoreClosedError
from rosaos.kernel.event_store import EventStore


def typed(text: str, key: str | None = None) -> UserTypedEvent:
    return UserTypedEvent(kind="user_typed", source="test", payload=UserText(text=text), idempotency_key=key)


def committed_rows(path: Path) -> list[tuple[int, str]]:
    """Read the file with a second, independent connection: only committed rows are visible."""
    with sqlite3.connect(path) as connection:
        return connection.execute("SELECT id, payload FROM events ORDER BY id").fetchall()


async def test_append_commits_before_returning_the_id(store: EventStore, tmp_path: Path) -> None:
    appended = await store.append(typed("turn on the kitchen light"))
    assert appended.duplicate is False
    assert committed_rows(tmp_path / "kernel.sqlite3") == [
        (appended.id, '{"text":"turn on the kitchen light"}')
    ]


async def test_ids_increase_in_append_order(store: EventStore) -> None:
    ids = [(await store.append(typed(f"message {n}"))).id for n in range(5)]
    assert ids == sorted(ids)
    assert len(set(ids)) == 5


async def test_a_repeated_idempotency_key_returns_the_first_id_and_enqueues_nothing(
    store: EventStore,
) -> None:
    first = await store.append(typed("hello", key="retry-1"))
    again = await store.append(typed("hello, a different body", key="retry-1"))
    assert again.id == first.id
    assert again.duplicate is True
    assert await store.pending_count() == 1
    event = await store.get(first.id)
    assert event is not None
    assert event.payload == UserText(text="hello")


async def test_concurrent_retries_with_one_key_enqueue_one_event(store: EventStore) -> None:
    results = await asyncio.gather(*(store.append(typed("hello", key="same")) for _ in range(20)))
    assert len({result.id for result in results}) == 1
    assert sorted(result.duplicate for result in results) == [False] + [True] * 19
    assert await store.pending_count() == 1


async def test_duplicates_do_not_use_up_ids(store: EventStore) -> None:
    first = await store.append(typed("a", key="k"))
    await store.append(typed("a", key="k"))
    second = await store.append(typed("b"))
    assert second.id == first.id + 1


async def test_next_pending_returns_the_oldest_unhandled_event_until_it_is_handled(store: EventStore) -> None:
    first = await store.append(typed("first"))
    await store.append(typed("second"))
    pending = await store.next_pending()
    assert pending is not None
    assert pending.id == first.id
    assert pending.handled is False
    # Not acknowledged yet: it is delivered again (at least once), with the attempt counted.
    again = await store.next_pending()
    assert again is not None
    assert again.id == first.id
    assert again.attempts == 2
    assert await store.mark_handled(first.id) is True
    following = await store.next_pending()
    assert following is not None
    assert following.payload == UserText(text="second")


async def test_mark_handled_twice_is_harmless_and_unknown_ids_are_an_error(store: EventStore) -> None:
    appended = await store.append(typed("hello"))
    assert await store.mark_handled(appended.id) is True
    assert await store.mark_handled(appended.id) is False
    with pytest.raises(KeyError, match="no event 999"):
        await store.mark_handled(999)
    event = await store.get(appended.id)
    assert event is not None
    assert event.handled is True


async def test_next_pending_is_none_when_everything_is_handled(store: EventStore) -> None:
    assert await store.next_pending() is None
    appended = await store.append(typed("hello"))
    await store.mark_handled(appended.id)
    assert await store.next_pending() is None
    assert await store.pending_count() == 0


async def test_unhandled_events_survive_reopening_in_order(tmp_path: Path) -> None:
    path = tmp_path / "kernel.sqlite3"
    store = await EventStore.open(path)
    ids = [(await store.append(typed(f"message {n}"))).id for n in range(4)]
    await store.mark_handled(ids[1])
    taken = await store.next_pending()  # the kernel was handling ids[0] when it "crashed"
    assert taken is not None
    assert taken.id == ids[0]
    await store.close()

    reopened = await EventStore.open(path)
    delivered = []
    while (event := await reopened.next_pending()) is not None:
        delivered.append(event.id)
        await reopened.mark_handled(event.id)
    await reopened.close()
    assert delivered == [ids[0], ids[2], ids[3]]


async def test_idempotency_keys_are_remembered_across_restarts(tmp_path: Path) -> None:
    path = tmp_path / "kernel.sqlite3"
    store = await EventStore.open(path)
    first = await store.append(typed("hello", key="k1"))
    await store.close()
    reopened = await EventStore.open(path)
    again = await reopened.append(typed("hello", key="k1"))
    assert (again.id, again.duplicate, again.conflict) == (first.id, True, False)
    await reopened.close()


async def test_wait_for_pending_wakes_when_an_event_is_appended(store: EventStore) -> None:
    waiter = asyncio.create_task(store.wait_for_pending())
    await asyncio.sleep(0)
    assert not waiter.done()
    await store.append(typed("wake up"))
    async with asyncio.timeout(5):
        await waiter


async def test_wait_for_pending_returns_at_once_when_events_are_waiting(store: EventStore) -> None:
    await store.append(typed("already here"))
    async with asyncio.timeout(5):
        await store.wait_for_pending()


async def test_events_round_trip_with_their_typed_payloads(store: EventStore) -> None:
    callback = WorkerCallback(process_id=7, status="ok", output="the light is on", tool_calls=1)
    notice = DeviceNotice(device="vacuum", message="bumped into a chair", data={"x": 1.5})
    ids = [
        (
            await store.append(WorkerCallbackEvent(kind="worker_callback", source="worker", payload=callback))
        ).id,
        (await store.append(DeviceNoticeEvent(kind="device_notice", source="vacuum", payload=notice))).id,
    ]
    stored = [await store.get(event_id) for event_id in ids]
    assert [event.payload for event in stored if event] == [callback, notice]
    assert [event.kind for event in stored if event] == ["worker_callback", "device_notice"]
    assert await store.get(12345) is None


@pytest.mark.parametrize("text", ["", "   ", "x" * 4001])
def test_user_text_must_be_present_and_bounded(text: str) -> None:
    with pytest.raises(ValidationError):
        UserText(text=text)


def test_user_text_is_stripped() -> None:
    assert UserText(text="  hello \n").text == "hello"


def test_an_unknown_kind_is_rejected() -> None:
    with pytest.raises(ValidationError, match="does not match any of the expected tags"):
        NEW_EVENT.validate_python({"kind": "telepathy", "payload": {"text": "hi"}})


async def test_a_stored_payload_that_no_longer_validates_is_delivered_as_an_error(
    store: EventStore, tmp_path: Path
) -> None:
    appended = await store.append(typed("hello"))
    with sqlite3.connect(tmp_path / "kernel.sqlite3") as connection:
        connection.execute("UPDATE events SET payload = '{\"words\": 1}' WHERE id = ?", (appended.id,))
    event = await store.next_pending()
    assert event is not None
    assert event.kind == "error"
    assert f"stored user_typed event {appended.id} cannot be read" in event.payload.model_dump()["message"]


async def test_process_ids_stay_unique_across_restarts(tmp_path: Path) -> None:
    path = tmp_path / "kernel.sqlite3"
    store = await EventStore.open(path)
    first, second = await store.next_process_id(), await store.next_process_id()
    await store.note_process_id(10)  # a manager counted up from first_process_id to 10
    await store.close()
    reopened = await EventStore.open(path)
    after_restart = await reopened.next_process_id()
    await reopened.close()
    assert (first, second) == (1, 2)
    assert after_restart == 11


async def test_kernel_values_are_kept_as_json(store: EventStore) -> None:
    assert await store.get_value("emergency_stop") is None
    await store.set_value("emergency_stop", {"latched": True, "by": "web"})
    await store.set_value("emergency_stop", {"latched": False})
    assert await store.get_value("emergency_stop") == {"latched": False}


async def test_a_closed_store_says_so(tmp_path: Path) -> None:
    store = await EventStore.open(tmp_path / "kernel.sqlite3")
    await store.close()
    with pytest.raises(StoreClosedError, match="closed"):
        await store.append(typed("too late"))


async def test_the_file_is_in_wal_mode(store: EventStore, tmp_path: Path) -> None:
    with sqlite3.connect(tmp_path / "kernel.sqlite3") as connection:
        assert connection.execute("PRAGMA journal_mode").fetchone() == ("wal",)
