"""The updates stream: persisted, paged by id, followed in order by any number of clients."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator
from pathlib import Path

from rosaos.events.types import UserText, UserTypedEvent
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.updates import Update, UpdateStream

from .kernel_support import eventually


async def take(stream: AsyncIterator[Update], count: int) -> list[Update]:
    async with asyncio.timeout(10):
        return [await anext(stream) for _ in range(count)]


async def test_publish_persists_and_after_pages_by_id(updates: UpdateStream) -> None:
    ids = [await updates.publish("notice", f"line {n}", {"n": n}) for n in range(5)]
    page = await updates.after(ids[1], limit=2)
    assert [update.id for update in page] == ids[2:4]
    assert page[0].text == "line 2"
    assert page[0].data == {"n": 2}
    assert await updates.after(ids[-1]) == []
    assert await updates.last_id() == ids[-1]


async def test_recent_returns_the_last_updates_oldest_first(updates: UpdateStream) -> None:
    for n in range(5):
        await updates.publish("notice", f"line {n}")
    assert [update.text for update in await updates.recent(2)] == ["line 3", "line 4"]


async def test_updates_survive_reopening(tmp_path: Path) -> None:
    store = await EventStore.open(tmp_path / "kernel.sqlite3")
    stream = await UpdateStream.open(store.database)
    await stream.publish("kernel_reply", "The kitchen light is on.", event_id=3)
    await store.close()
    reopened = await EventStore.open(tmp_path / "kernel.sqlite3")
    page = await (await UpdateStream.open(reopened.database)).after(0)
    await reopened.close()
    assert [(update.kind, update.text, update.event_id) for update in page] == [
        ("kernel_reply", "The kitchen light is on.", 3)
    ]


async def test_publish_event_describes_the_event(updates: UpdateStream) -> None:
    event = UserTypedEvent(kind="user_typed", source="web", payload=UserText(text="hello"))
    update_id = await updates.publish_event(41, event)
    [update] = await updates.after(update_id - 1)
    assert update.kind == "event"
    assert update.text == "[User typed] hello"
    assert update.event_id == 41
    assert update.data == {"kind": "user_typed", "source": "web", "payload": {"text": "hello"}}


async def test_follow_replays_the_backlog_then_new_updates_in_order(updates: UpdateStream) -> None:
    first = await updates.publish("notice", "before 1")
    await updates.publish("notice", "before 2")
    stream = updates.follow(after_id=first)
    backlog = await take(stream, 1)
    await updates.publish("notice", "after 1")
    await updates.publish("notice", "after 2")
    live = await take(stream, 2)
    assert [update.text for update in backlog + live] == ["before 2", "after 1", "after 2"]
    await stream.aclose()
    assert updates.follower_count == 0


async def test_many_followers_each_get_every_update(updates: UpdateStream) -> None:
    streams = [updates.follow() for _ in range(5)]
    readers = [asyncio.create_task(take(stream, 3)) for stream in streams]
    await eventually(lambda: updates.follower_count == 5, message="five followers subscribing")
    for n in range(3):
        await updates.publish("notice", f"n{n}")
    results = await asyncio.gather(*readers)
    assert all([update.text for update in result] == ["n0", "n1", "n2"] for result in results)
    for stream in streams:
        await stream.aclose()


async def test_a_slow_follower_never_blocks_publish_and_catches_up_without_gaps(
    store: EventStore, updates: UpdateStream
) -> None:
    small = UpdateStream(store.database, follower_queue_size=4)
    stream = small.follow()
    reader = asyncio.create_task(take(stream, 1))  # subscribes, then sits on the first update
    await eventually(lambda: small.follower_count == 1, message="the follower subscribing")
    # Far more than the follower's queue holds: publish must still return every time.
    async with asyncio.timeout(10):
        for n in range(50):
            await small.publish("notice", f"n{n}")
    first = await reader
    rest = await take(stream, 49)
    assert [update.text for update in first + rest] == [f"n{n}" for n in range(50)]
    await stream.aclose()


async def test_a_stopped_follower_unsubscribes(updates: UpdateStream) -> None:
    stream = updates.follow()
    reader = asyncio.create_task(anext(stream))
    await eventually(lambda: updates.follower_count == 1, message="the follower subscribing")
    reader.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await reader
    await stream.aclose()
    assert updates.follower_count == 0
