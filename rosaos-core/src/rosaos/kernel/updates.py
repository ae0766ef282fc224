"""The updates stream: everything the kernel does, as the web page and the CLI follow it.

Every kernel output (an event received, a reply, a process launched or ended, a tool call, an
error) is published here. Updates are persisted in the same SQLite file as the events (table
``updates``), so a client that reconnects resumes from the last id it saw, even across restarts.

Fan-out is in memory: each follower has a bounded queue. :meth:`UpdateStream.publish` never
waits for a follower; a follower whose queue is full is marked as lagging and catches up from the
table. A slow or stuck client therefore never slows the kernel, and never misses an update.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import sqlite3
import time
from collections.abc import AsyncIterator, Sequence
from datetime import UTC, datetime
from typing import Any, Literal

from pydantic import BaseModel

from rosaos.events.callback import WorkerCallback
from rosaos.events.types import DeviceNotice, Event, NewEvent, TimerFired, UserText
from rosaos.kernel.database import Database
from rosaos.kernel.event_store import mark_handled_in

UpdateKind = Literal[
    "event", "kernel_reply", "process_launched", "process_ended", "tool_call", "error", "notice"
]
"""``event``: an event was received. ``kernel_reply``: the kernel answered the user.
``process_launched`` / ``process_ended``: a process started or finished. ``tool_call``: the kernel
called one of its tools. ``error``: something failed. ``notice``: anything else worth showing."""

FOLLOWER_QUEUE_SIZE = 256
CATCH_UP_BATCH = 200

_SCHEMA = """
CREATE TABLE IF NOT EXISTS updates (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    time REAL NOT NULL,
    kind TEXT NOT NULL,
    text TEXT NOT NULL,
    data TEXT NOT NULL,
    event_id INTEGER
);
"""
_COLUMNS = "id, time, kind, text, data, event_id"
log = logging.getLogger(__name__)


class Update(BaseModel):
    """One line of the updates stream."""

    id: int
    time: datetime
    kind: UpdateKind
    text: str
    """What a person reads: ``[User typed] hello``, ``Launched process 7 on kitchen_light``."""
    data: dict[str, Any]
    """Machine-readable details (event kind and payload, process id, tool arguments, ...)."""
    event_id: int | None = None
    """The event this update belongs to, if any."""


def describe_event(event: Event | NewEvent) -> str:
    """One line for people and the kernel model: ``[User said] turn on the light``."""
    payload = event.payload
    if isinstance(payload, UserText):
        label = "User said" if event.kind == "user_said" else "User typed"
        return f"[{label}] {payload.text}"
    if isinstance(payload, WorkerCallback):
        parts = [f"process={payload.process_id}", f"status={payload.status}"]
        if payload.output:
            parts.append(f"output={payload.output}")
        if payload.error:
            parts.append(f"error={payload.error}")
        return "[Process callback] " + " ".join(parts)
    if isinstance(payload, DeviceNotice):
        return f"[Device notice] {payload.device}: {payload.message}"
    if isinstance(payload, TimerFired):
        return f"[Timer fired] timer {payload.timer_id}: {payload.action}"
    cause = f" (event {payload.source_event})" if payload.source_event else ""
    return f"[Error]{cause} {payload.message}"


class _Follower:
    """One subscriber's bounded queue, and whether it overflowed."""

    def __init__(self, size: int) -> None:
        self.queue: asyncio.Queue[Update] = asyncio.Queue(size)
        self.lagging = False

    def offer(self, update: Update) -> None:
        if self.lagging:
            return
        try:
            self.queue.put_nowait(update)
        except asyncio.QueueFull:
            # Dropping is safe: the follower re-reads everything after its last id from the table.
            self.lagging = True


class UpdateStream:
    """Publish kernel outputs and follow them. Shares the event store's :class:`Database`."""

    def __init__(self, database: Database, follower_queue_size: int = FOLLOWER_QUEUE_SIZE) -> None:
        self._database = database
        self._followers: set[_Follower] = set()
        self._queue_size = follower_queue_size

    @classmethod
    async def open(cls, database: Database) -> UpdateStream:
        """Create the ``updates`` table if needed. Pass ``event_store.database``."""
        await database.executescript(_SCHEMA)
        return cls(database)

    async def publish(
        self,
        kind: UpdateKind,
        text: str,
        data: dict[str, Any] | None = None,
        event_id: int | None = None,
    ) -> int:
        """Persist one update, hand it to every follower without waiting, and return its id."""
        [update_id] = await self._publish([(kind, text, data)], event_id, mark_handled=False)
        return update_id

    async def publish_and_mark_handled(
        self, event_id: int, items: Sequence[tuple[UpdateKind, str, dict[str, Any]]]
    ) -> list[int]:
        """Publish what the kernel did for an event and mark it handled, in one transaction.

        A kernel killed at any point therefore shows an event's outputs exactly once: either
        none of them (the event is redelivered) or all of them (it is not).
        """
        return await self._publish(items, event_id, mark_handled=True)

    async def publish_batch_and_mark_handled(
        self, event_ids: Sequence[int], items: Sequence[tuple[UpdateKind, str, dict[str, Any]]]
    ) -> list[int]:
        """Publish what the kernel did for events it handled in one turn, and mark them all handled.

        The outputs belong to the last event; each earlier one gets a ``notice`` whose data says
        ``handled_with`` that event, so a chat following an earlier message follows the turn too.
        One transaction, as for a single event.
        """
        if len(event_ids) == 1:
            return await self.publish_and_mark_handled(event_ids[0], items)
        *earlier, last = event_ids
        groups: list[tuple[int | None, Sequence[tuple[UpdateKind, str, dict[str, Any] | None]]]] = [
            (event_id, [("notice", f"handled together with event {last}", {"handled_with": last})])
            for event_id in earlier
        ]
        groups.append((last, items))
        return await self._publish_groups(groups, mark_handled=True)

    async def _publish(
        self,
        items: Sequence[tuple[UpdateKind, str, dict[str, Any] | None]],
        event_id: int | None,
        mark_handled: bool,
    ) -> list[int]:
        return await self._publish_groups([(event_id, items)], mark_handled)

    async def _publish_groups(
        self,
        groups: Sequence[tuple[int | None, Sequence[tuple[UpdateKind, str, dict[str, Any] | None]]]],
        mark_handled: bool,
    ) -> list[int]:
        """Insert each group's updates under its event (and mark it handled), all in one transaction."""
        at = time.time()
        encoded = [
            (event_id, [(kind, text, json.dumps(data or {}, default=str)) for kind, text, data in items])
            for event_id, items in groups
        ]
        ids = await self._database.run(lambda connection: _insert(connection, encoded, at, mark_handled))
        self._offer(ids, encoded, at)
        return ids

    def _offer(self, ids: list[int], encoded: _Encoded, at: float) -> None:
        """Hand committed updates to every follower, without waiting for any."""
        flat = [(event_id, row) for event_id, rows in encoded for row in rows]
        for update_id, (event_id, (kind, text, data)) in zip(ids, flat, strict=True):
            update = Update(
                id=update_id,
                time=datetime.fromtimestamp(at, UTC),
                kind=kind,
                text=text,
                data=json.loads(data),
                event_id=event_id,
            )
            for follower in list(self._followers):
                follower.offer(update)

    def event_update(self, event: NewEvent) -> EventUpdate:
        """The ``event`` update of ``event``, to write in the transaction that appends it.

        The intake passes :meth:`EventUpdate.write` to :meth:`EventStore.append`, so a ``POST /chat``
        makes one trip to the database thread, not two (issue 26's enqueue rate), and the update is
        committed with the event it describes.
        """
        return EventUpdate(self, event)

    async def publish_event(self, event_id: int, event: NewEvent) -> int:
        """Publish the ``event`` update for an event already appended to the store."""
        return await self.publish("event", describe_event(event), _event_data(event), event_id=event_id)

    async def after(self, update_id: int, limit: int = 100) -> list[Update]:
        """Up to ``limit`` updates with an id above ``update_id``, oldest first."""
        rows = await self._database.fetch(
            f"SELECT {_COLUMNS} FROM updates WHERE id > ? ORDER BY id LIMIT ?", (update_id, limit)
        )
        return [_update(row) for row in rows]

    async def recent(self, limit: int = 100) -> list[Update]:
        """The last ``limit`` updates, oldest first."""
        rows = await self._database.fetch(
            f"SELECT {_COLUMNS} FROM updates ORDER BY id DESC LIMIT ?", (limit,)
        )
        return [_update(row) for row in reversed(rows)]

    async def last_id(self) -> int:
        """The id of the newest update, 0 when there is none."""
        rows = await self._database.fetch("SELECT coalesce(max(id), 0) FROM updates")
        return int(rows[0][0])

    async def follow(self, after_id: int = 0) -> AsyncIterator[Update]:
        """Every update with an id above ``after_id``, in id order, then new ones as they come.

        Never ends on its own; stop iterating (or cancel) to unsubscribe.
        """
        follower = _Follower(self._queue_size)
        # Subscribe before reading the table, so nothing published in between is missed;
        # an update seen both ways is skipped by id.
        self._followers.add(follower)
        try:
            last = after_id
            catching_up = True
            while True:
                if catching_up or follower.lagging:
                    follower.lagging = False
                    _drain(follower.queue)
                    batch = await self.after(last, CATCH_UP_BATCH)
                    for update in batch:
                        yield update
                        last = update.id
                    catching_up = len(batch) == CATCH_UP_BATCH
                    continue
                update = await follower.queue.get()
                if update.id <= last:
                    continue
                if update.id != last + 1:
                    # A gap (published by another process, or handed over out of order):
                    # the table is the truth, so re-read from it, this update included.
                    catching_up = True
                    continue
                yield update
                last = update.id
        finally:
            self._followers.discard(follower)

    @property
    def follower_count(self) -> int:
        """How many clients follow the stream now."""
        return len(self._followers)


class EventUpdate:
    """An ``event`` update written with its event's append (:meth:`UpdateStream.event_update`)."""

    def __init__(self, stream: UpdateStream, event: NewEvent) -> None:
        self._stream = stream
        self._at = time.time()
        self._row: tuple[UpdateKind, str, str] = (
            "event",
            describe_event(event),
            json.dumps(_event_data(event), default=str),
        )
        self._written: tuple[int, int] | None = None

    def write(self, connection: sqlite3.Connection, event_id: int) -> None:
        """On the database thread, inside the append's transaction: insert the update.

        In a savepoint of its own: an update that cannot be written is logged and left out, and the
        event is still queued, as when publishing failed after the append.
        """
        connection.execute("SAVEPOINT event_update")
        try:
            [update_id] = _insert(connection, [(event_id, [self._row])], self._at, mark_handled=False)
        except sqlite3.Error:
            connection.execute("ROLLBACK TO event_update")
            log.exception("could not write the update for event %s", event_id)
            return
        finally:
            connection.execute("RELEASE event_update")
        self._written = (event_id, update_id)

    def offer(self) -> None:
        """Once the append is committed: hand the update to the followers (if it was written)."""
        if self._written is not None:
            event_id, update_id = self._written
            self._stream._offer([update_id], [(event_id, [self._row])], self._at)


_Encoded = Sequence[tuple[int | None, Sequence[tuple[str, str, str]]]]
"""Updates ready for the table: per event id, (kind, text, JSON data) rows."""


def _insert(connection: sqlite3.Connection, encoded: _Encoded, at: float, mark_handled: bool) -> list[int]:
    """Insert ``encoded`` (and mark each event handled if asked); the new ids, in order."""
    ids = []
    for event_id, rows in encoded:
        for kind, text, data in rows:
            ids.append(
                int(
                    connection.execute(
                        "INSERT INTO updates (time, kind, text, data, event_id) VALUES (?, ?, ?, ?, ?) RETURNING id",
                        (at, kind, text, data, event_id),
                    ).fetchall()[0][0]
                )
            )
        if mark_handled and event_id is not None:
            mark_handled_in(connection, event_id)
    return ids


def _event_data(event: NewEvent) -> dict[str, Any]:
    return {"kind": event.kind, "source": event.source, "payload": event.payload.model_dump(mode="json")}


def _drain(queue: asyncio.Queue[Update]) -> None:
    with contextlib.suppress(asyncio.QueueEmpty):
        while True:
            queue.get_nowait()


def _update(row: tuple[Any, ...]) -> Update:
    update_id, at, kind, text, data, event_id = row
    return Update(
        id=update_id,
        time=datetime.fromtimestamp(at, UTC),
        kind=kind,
        text=text,
        data=json.loads(data),
        event_id=event_id,
    )
