"""Appends events to the store given on the command line until it is killed (test_durability).

Each line on stdout reports something already committed: ``appended ID N`` or ``handled ID``.
Every other event is marked handled, as a kernel working through the queue would. With a second
argument ``TASKS``, that many appenders run at once (event ``N`` is appended by task ``N % TASKS``),
so the store commits them in groups, as it does for concurrent ``POST /chat``.
"""

from __future__ import annotations

import asyncio
import sys
from pathlib import Path

from rosaos.events.types import UserText, UserTypedEvent
from rosaos.kernel.event_store import EventStore


async def main(path: Path, tasks: int) -> None:
    store = await EventStore.open(path)
    await asyncio.gather(*(append_forever(store, first, tasks) for first in range(tasks)))


async def append_forever(store: EventStore, n: int, step: int) -> None:
    while True:
        event = UserTypedEvent(
            kind="user_typed",
            source="durability",
            payload=UserText(text=f"event {n}"),
            idempotency_key=f"key-{n}",
        )
        appended = await store.append(event)
        print(f"appended {appended.id} {n}", flush=True)
        if n % 2 == 0:
            await store.mark_handled(appended.id)
            print(f"handled {appended.id}", flush=True)
        n += step


if __name__ == "__main__":
    asyncio.run(main(Path(sys.argv[1]), int(sys.argv[2]) if len(sys.argv) > 2 else 1))
