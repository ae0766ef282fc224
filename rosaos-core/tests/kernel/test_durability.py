"""A process killed with SIGKILL loses nothing it committed, and a retried POST is not doubled."""

from __future__ import annotations

import asyncio
import signal
import sys
from pathlib import Path

import pytest

from rosaos.events.types import UserText, UserTypedEvent
from rosaos.kernel.event_store import EventStore

pytestmark = pytest.mark.slow

APPENDER = Path(__file__).parent / "append_until_killed.py"
ACKNOWLEDGED_BEFORE_KILL = 150


async def run_until_killed(path: Path, tasks: int = 1) -> tuple[dict[int, int], set[int]]:
    """Run the appender (``tasks`` appending at once), SIGKILL it mid-stream; return
    {event id: n} acknowledged and ids handled."""
    process = await asyncio.create_subprocess_exec(
        sys.executable, str(APPENDER), str(path), str(tasks), stdout=asyncio.subprocess.PIPE
    )
    assert process.stdout is not None
    acknowledged: dict[int, int] = {}
    handled: set[int] = set()

    def record(line: bytes) -> None:
        words = line.decode().split()
        if len(words) == 3 and words[0] == "appended":
            acknowledged[int(words[1])] = int(words[2])
        elif len(words) == 2 and words[0] == "handled":
            handled.add(int(words[1]))

    try:
        async with asyncio.timeout(30):
            while len(acknowledged) < ACKNOWLEDGED_BEFORE_KILL:
                line = await process.stdout.readline()
                assert line, "the appender exited on its own"
                record(line)
    finally:
        process.send_signal(signal.SIGKILL)
    # Lines already written before the kill are still in the pipe: they were committed too.
    for line in (await process.stdout.read()).splitlines():
        record(line)
    await process.wait()
    return acknowledged, handled


async def test_every_committed_event_is_there_exactly_once_after_sigkill(tmp_path: Path) -> None:
    path = tmp_path / "kernel.sqlite3"
    acknowledged, handled = await run_until_killed(path)

    store = await EventStore.open(path)
    try:
        stored = {}
        for event_id in range(1, max(acknowledged) + 3):
            event = await store.get(event_id)
            if event is not None:
                stored[event.id] = event
        # Every acknowledged append is there, with its own body, once.
        for event_id, n in acknowledged.items():
            assert stored[event_id].idempotency_key == f"key-{n}"
            assert stored[event_id].payload == UserText(text=f"event {n}")
        keys = [event.idempotency_key for event in stored.values()]
        assert len(keys) == len(set(keys))
        # At most one append was committed but not yet acknowledged when the kill came.
        assert len(stored) - len(acknowledged) in (0, 1)
        assert all(stored[event_id].handled for event_id in handled)

        # The client retries the append that was in flight: it is enqueued exactly once in total.
        in_flight = max(acknowledged.values()) + 1
        was_committed = any(event.idempotency_key == f"key-{in_flight}" for event in stored.values())
        retry = UserTypedEvent(
            kind="user_typed",
            source="durability",
            payload=UserText(text=f"event {in_flight}"),
            idempotency_key=f"key-{in_flight}",
        )
        retried = await store.append(retry)
        assert retried.duplicate is was_committed
        again = await store.append(retry)
        assert (again.id, again.duplicate, again.conflict) == (retried.id, True, False)

        # The kill may also come between a handling's commit and its report: at most the last
        # acknowledged event the appender was to handle is handled without our hearing of it.
        unreported = {i for i, n in acknowledged.items() if n % 2 == 0 and i not in handled}
        assert unreported <= {max(acknowledged)}
        handled |= {i for i in unreported if stored[i].handled}

        # After the restart the kernel gets every unhandled event, in id order, each once.
        delivered = []
        while (event := await store.next_pending()) is not None:
            delivered.append(event.id)
            await store.mark_handled(event.id)
        unhandled = sorted(set(stored) - handled)
        assert delivered == (unhandled if was_committed else [*unhandled, retried.id])
    finally:
        await store.close()


async def test_appends_committed_together_are_each_there_after_sigkill(tmp_path: Path) -> None:
    """Seven appenders at once: the store commits their appends in groups (``Database``'s group
    commit), and still no id is answered before its group is on disk."""
    tasks = 7
    path = tmp_path / "kernel.sqlite3"
    acknowledged, handled = await run_until_killed(path, tasks)

    store = await EventStore.open(path)
    try:
        stored = {}
        for event_id in range(1, max(acknowledged) + tasks + 2):
            event = await store.get(event_id)
            if event is not None:
                stored[event.id] = event
        for event_id, n in acknowledged.items():
            assert stored[event_id].idempotency_key == f"key-{n}"
            assert stored[event_id].payload == UserText(text=f"event {n}")
        keys = [event.idempotency_key for event in stored.values()]
        assert len(keys) == len(set(keys))
        # Each appender had at most one append in flight when the kill came.
        assert 0 <= len(stored) - len(acknowledged) <= tasks
        assert all(stored[event_id].handled for event_id in handled)
        assert sorted(stored) == list(range(1, len(stored) + 1)), "ids are given without gaps"
    finally:
        await store.close()
