"""The intake: every event is appended, then published once, then its side effects run."""

from __future__ import annotations

from rosaos.events.types import UserText, UserTypedEvent, WorkerCallbackEvent
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.intake import Intake, Queued
from rosaos.kernel.process_ends import end_event
from rosaos.kernel.updates import UpdateStream
from rosaos.processes.jobs import WorkerCallback

from .kernel_support import eventually


def typed(text: str, key: str | None = None) -> UserTypedEvent:
    return UserTypedEvent(kind="user_typed", source="chat", payload=UserText(text=text), idempotency_key=key)


async def test_an_event_is_committed_and_published_before_its_side_effects_run(
    store: EventStore, updates: UpdateStream
) -> None:
    intake = Intake(store, updates)
    seen: list[tuple[int, bool, int]] = []

    async def effect(queued: Queued) -> None:
        event = await store.get(queued.id)
        published = [u for u in await updates.recent() if u.event_id == queued.id and u.kind == "event"]
        seen.append((queued.id, event is not None, len(published)))

    intake.on("user_typed", effect)
    queued = await intake.submit(typed("turn on the lamp"))
    assert seen == [(queued.id, True, 1)]


async def test_effects_run_only_for_their_kind_and_in_the_order_registered(
    store: EventStore, updates: UpdateStream
) -> None:
    intake = Intake(store, updates)
    order: list[str] = []

    async def first(queued: Queued) -> None:
        order.append("first")

    async def second(queued: Queued) -> None:
        order.append("second")

    async def other(queued: Queued) -> None:
        order.append("other")

    intake.on("user_typed", first)
    intake.on("user_typed", second)
    intake.on("user_said", other)
    await intake.submit(typed("hello"))
    assert order == ["first", "second"]


async def test_a_duplicate_is_not_published_again_and_its_effects_see_the_first_event(
    store: EventStore, updates: UpdateStream
) -> None:
    """Orphan recovery reports ``crashed`` for a process whose own end was already committed:
    the effects must see the end that is in the queue, not the late guess."""
    intake = Intake(store, updates)
    seen: list[Queued] = []

    async def effect(queued: Queued) -> None:
        seen.append(queued)

    intake.on("worker_callback", effect)
    done = await intake.submit(end_event(WorkerCallback(process_id=4, status="ok", output="lamp on")))
    crash = end_event(
        WorkerCallback(process_id=4, status="crashed", error="kernel restarted"), source="kernel"
    )
    again = await intake.submit(crash)
    assert (again.id, again.duplicate) == (done.id, True)
    assert isinstance(seen[1].event, WorkerCallbackEvent)
    assert seen[1].event.payload == WorkerCallback(process_id=4, status="ok", output="lamp on")
    assert [u.event_id for u in await updates.recent() if u.kind == "event"] == [done.id]
    assert await store.pending_count() == 1


async def test_a_reused_key_for_another_body_is_a_conflict_and_queues_nothing_new(
    store: EventStore, updates: UpdateStream
) -> None:
    intake = Intake(store, updates)
    seen: list[Queued] = []

    async def effect(queued: Queued) -> None:
        seen.append(queued)

    intake.on("user_typed", effect)
    first = await intake.submit(typed("hello", key="k"))
    reused = await intake.submit(typed("goodbye", key="k"))
    assert (reused.id, reused.conflict) == (first.id, True)
    assert [q.event.payload for q in seen] == [UserText(text="hello")] * 2  # never the reused body
    assert await store.pending_count() == 1


async def test_a_failing_effect_leaves_the_event_queued_and_says_so_on_the_updates_stream(
    store: EventStore, updates: UpdateStream
) -> None:
    intake = Intake(store, updates)

    async def broken(queued: Queued) -> None:
        raise RuntimeError("lease table unavailable")

    async def after(queued: Queued) -> None:
        ran.append(queued.id)

    ran: list[int] = []
    intake.on("user_typed", broken)
    intake.on("user_typed", after)
    queued = await intake.submit(typed("hello"))
    assert await store.get(queued.id) is not None
    assert ran == [queued.id]  # one broken effect does not skip the next
    await eventually(lambda: _error_published(updates, "lease table unavailable"))


async def test_the_event_update_is_written_with_the_event_and_reaches_a_follower(
    store: EventStore, updates: UpdateStream
) -> None:
    # One trip to the database per event: the update is committed in the append's transaction,
    # then handed to the followers, who see it live, once, under the event's id.
    intake = Intake(store, updates)
    follower = updates.follow(after_id=await updates.last_id())
    queued = await intake.submit(typed("turn on the lamp"))
    update = await anext(follower)
    await follower.aclose()
    assert (update.kind, update.event_id, update.text) == (
        "event",
        queued.id,
        "[User typed] turn on the lamp",
    )
    assert [u.id for u in await updates.recent() if u.event_id == queued.id] == [update.id]


async def test_an_event_whose_update_cannot_be_written_is_still_queued(
    store: EventStore, updates: UpdateStream
) -> None:
    # The update is written in a savepoint of its own: its failure never un-queues the event.
    intake = Intake(store, updates)
    await store.database.execute("DROP TABLE updates")
    queued = await intake.submit(typed("hello"))
    assert await store.get(queued.id) is not None
    assert await store.pending_count() == 1


async def _error_published(updates: UpdateStream, text: str) -> bool:
    return any(u.kind == "error" and text in u.text for u in await updates.recent())
