"""The kernel's durable event queue: typed events in a SQLite file in the data directory.

Every input to the kernel (user speech, typed chat, a worker callback, a device notice, an error)
is an event. :meth:`EventStore.append` commits it before returning its id, so ``202`` from the API
means "on disk". Delivery is at least once: the kernel loop reads :meth:`EventStore.next_pending`,
handles the event, and only then calls :meth:`EventStore.mark_handled`. An event the kernel was
handling when it crashed is delivered again after restart, in id order. A repeated idempotency
key returns the first event's id and enqueues nothing, so a retried POST is not processed twice.

The kernel loop, in short::

    while True:
        event = await store.next_pending()
        if event is None:
            await store.wait_for_pending()
            continue
        await handle(event)              # may run twice after a crash: keep it safe to repeat
        await store.mark_handled(event.id)
"""

from __future__ import annotations

import asyncio
import json
import sqlite3
import time
from collections.abc import Callable, Mapping
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from rosaos.events.types import NEW_EVENT, Appended, ErrorEvent, ErrorReport, Event, NewEvent
from rosaos.kernel.database import Database

_SCHEMA = """
CREATE TABLE IF NOT EXISTS events (
    id INTEGER PRIMARY KEY AUTOINCREMENT,  -- AUTOINCREMENT: an id is never reused
    time REAL NOT NULL,
    kind TEXT NOT NULL,
    source TEXT NOT NULL,
    payload TEXT NOT NULL,
    idempotency_key TEXT UNIQUE,           -- NULLs never collide; the index makes retries race-safe
    attempts INTEGER NOT NULL DEFAULT 0,
    handled_at REAL
);
CREATE INDEX IF NOT EXISTS events_pending ON events (id) WHERE handled_at IS NULL;
CREATE TABLE IF NOT EXISTS process_ids (
    id INTEGER PRIMARY KEY AUTOINCREMENT,  -- sqlite_sequence remembers the highest id ever given
    time REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS kv (key TEXT PRIMARY KEY, value TEXT NOT NULL);
"""

_COLUMNS = "id, time, kind, source, payload, idempotency_key, attempts, handled_at"


def mark_handled_in(connection: sqlite3.Connection, event_id: int) -> bool:
    """Mark an event handled inside the caller's transaction (see :meth:`EventStore.mark_handled`)."""
    changed = connection.execute(
        "UPDATE events SET handled_at = ? WHERE id = ? AND handled_at IS NULL",
        (time.time(), event_id),
    ).rowcount
    if changed:
        return True
    if not connection.execute("SELECT 1 FROM events WHERE id = ?", (event_id,)).fetchall():
        raise KeyError(f"no event {event_id}")
    return False


class EventStore:
    """The durable event queue, process-id counter and small key-value state of the kernel.

    Open it with :meth:`open`; close it with :meth:`close`. All methods are coroutines that run
    their SQL on the database thread (see :class:`Database`).
    """

    def __init__(self, database: Database) -> None:
        self.database = database
        self._appended = asyncio.Event()

    @classmethod
    async def open(cls, path: Path) -> EventStore:
        """Open (or create) the store in the SQLite file ``path``, e.g. ``<data_dir>/kernel.sqlite3``."""
        database = await Database.open(path)
        try:
            await database.executescript(_SCHEMA)
        except BaseException:
            await database.close()
            raise
        return cls(database)

    async def close(self) -> None:
        """Close the database. Everything appended is already committed."""
        await self.database.close()

    async def append(
        self, event: NewEvent, also: Callable[[sqlite3.Connection, int], None] | None = None
    ) -> Appended:
        """Commit ``event`` and return its id; a known idempotency key returns the first id instead.

        ``also(connection, id)`` runs in the same transaction once a new event is inserted (not for
        a duplicate): the intake writes the event's update there, in the same trip to the database
        thread.
        """
        payload = event.payload.model_dump_json()
        key = event.idempotency_key

        def insert(connection: sqlite3.Connection) -> Appended:
            # Look first (an INSERT that hits the unique index would still use up an id). The
            # transaction holds the write lock, so no other writer slips in between; the unique
            # index stays as the guarantee.
            if key is not None:
                first = connection.execute(
                    "SELECT id, kind, payload FROM events WHERE idempotency_key = ?", (key,)
                ).fetchall()
                if first:
                    first_id, first_kind, first_payload = first[0]
                    differs = first_kind != event.kind or first_payload != payload
                    return Appended(first_id, duplicate=True, conflict=differs)
            inserted = connection.execute(
                "INSERT INTO events (time, kind, source, payload, idempotency_key) VALUES (?, ?, ?, ?, ?) "
                "RETURNING id",
                (time.time(), event.kind, event.source, payload, key),
            ).fetchall()
            if also is not None:
                also(connection, inserted[0][0])
            return Appended(inserted[0][0], duplicate=False)

        appended = await self.database.run(insert)
        if not appended.duplicate:
            self._appended.set()
        return appended

    async def get(self, event_id: int) -> Event | None:
        """The event with this id, or None."""
        rows = await self.database.fetch(f"SELECT {_COLUMNS} FROM events WHERE id = ?", (event_id,))
        return _event(rows[0]) if rows else None

    async def next_pending(self) -> Event | None:
        """The oldest event not yet handled, or None. Each call counts as one delivery attempt."""

        def take(connection: sqlite3.Connection) -> list[tuple[Any, ...]]:
            return connection.execute(
                "UPDATE events SET attempts = attempts + 1 WHERE id = "
                "(SELECT id FROM events WHERE handled_at IS NULL ORDER BY id LIMIT 1) "
                f"RETURNING {_COLUMNS}"
            ).fetchall()

        rows = await self.database.run(take)
        return _event(rows[0]) if rows else None

    async def take_pending(self, after: int, limit: int) -> list[Event]:
        """Up to ``limit`` more unhandled events after ``after``, oldest first; each counts as a delivery.

        The kernel takes them with the event it is about to handle, to read them in one turn.
        """

        def take(connection: sqlite3.Connection) -> list[tuple[Any, ...]]:
            return connection.execute(
                "UPDATE events SET attempts = attempts + 1 WHERE id IN "
                "(SELECT id FROM events WHERE handled_at IS NULL AND id > ? ORDER BY id LIMIT ?) "
                f"RETURNING {_COLUMNS}",
                (after, limit),
            ).fetchall()

        if limit <= 0:
            return []
        rows = await self.database.run(take)
        return sorted((_event(row) for row in rows), key=lambda event: event.id)

    async def mark_handled(self, event_id: int) -> bool:
        """Acknowledge an event once the kernel is done with it. False if it was already handled.

        Raises :class:`KeyError` for an id that was never appended.
        """

        return await self.database.run(lambda connection: mark_handled_in(connection, event_id))

    async def pending_count(self) -> int:
        """How many events wait for the kernel (including one being handled now)."""
        rows = await self.database.fetch("SELECT count(*) FROM events WHERE handled_at IS NULL")
        return int(rows[0][0])

    async def wait_for_pending(self) -> None:
        """Return once an event is pending.

        The wake-up comes from :meth:`append` in this process. Another process writing to the same
        file (a tool, a test) is only seen at the next call: wrap it in ``asyncio.timeout`` to poll.
        After a wake-up it returns without counting again: the append that woke it committed an
        event, and the caller's next :meth:`next_pending` reads it (one database hop fewer between
        a ``POST /chat`` and the kernel's turn; the count is only for a call with nothing to wake it).
        """
        # Clear before looking, so an append between the look and the wait still wakes us.
        self._appended.clear()
        if await self.pending_count():
            return
        await self._appended.wait()

    async def next_process_id(self) -> int:
        """A process id never given before, not even before a restart."""
        rows = await self.database.run(
            lambda connection: connection.execute(
                "INSERT INTO process_ids (time) VALUES (?) RETURNING id", (time.time(),)
            ).fetchall()
        )
        return int(rows[0][0])

    async def note_process_id(self, process_id: int) -> None:
        """Record an id handed out elsewhere (a manager counting up from ``first_process_id``).

        Later :meth:`next_process_id` calls return ids above it, also after a restart.
        """
        await self.database.execute(
            "INSERT OR IGNORE INTO process_ids (id, time) VALUES (?, ?)", (process_id, time.time())
        )

    async def set_values(self, values: Mapping[str, Any], note_process_id: int | None = None) -> None:
        """Store several JSON values (and note a process id, as :meth:`note_process_id`) in one commit.

        All or none, and one database hop: a launch records its id, its process and its cause
        before the worker has the job, and three commits in a row were a millisecond of that path.
        """
        rows = [(key, json.dumps(value)) for key, value in values.items()]

        def write(connection: sqlite3.Connection) -> None:
            if note_process_id is not None:
                connection.execute(
                    "INSERT OR IGNORE INTO process_ids (id, time) VALUES (?, ?)",
                    (note_process_id, time.time()),
                )
            connection.executemany(
                "INSERT INTO kv (key, value) VALUES (?, ?) ON CONFLICT (key) DO UPDATE SET value = excluded.value",
                rows,
            )

        await self.database.run(write)

    async def get_value(self, key: str) -> Any:
        """The kernel's own small state: the JSON value stored under ``key``, or None."""
        rows = await self.database.fetch("SELECT value FROM kv WHERE key = ?", (key,))
        return json.loads(rows[0][0]) if rows else None

    async def set_value(self, key: str, value: Any) -> None:
        """Store a JSON-serializable ``value`` under ``key``, replacing any previous one."""
        await self.database.execute(
            "INSERT INTO kv (key, value) VALUES (?, ?) ON CONFLICT (key) DO UPDATE SET value = excluded.value",
            (key, json.dumps(value)),
        )


def _event(row: tuple[Any, ...]) -> Event:
    event_id, at, kind, source, payload, key, attempts, handled_at = row
    try:
        body: NewEvent = NEW_EVENT.validate_python(
            {"kind": kind, "source": source, "payload": json.loads(payload), "idempotency_key": key}
        )
    except (ValidationError, ValueError) as error:
        # A row written by an older rosaOS whose payload no longer validates must not wedge the
        # kernel on every restart: it is delivered as an error the kernel can report and acknowledge.
        body = ErrorEvent(
            kind="error",
            source="store",
            payload=ErrorReport(
                message=f"stored {kind} event {event_id} cannot be read any more: {error}"[:4000],
                source_event=event_id,
            ),
        )
    return Event(
        id=event_id,
        time=datetime.fromtimestamp(at, UTC),
        kind=body.kind,
        source=body.source,
        payload=body.payload,
        idempotency_key=key,
        handled=handled_at is not None,
        attempts=attempts,
    )
