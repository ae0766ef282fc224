"""The activity log: every tool call of every process, with its result and safety decision.

Receipts (:class:`~rosaos.receipts.Receipt`) arrive in worker callbacks; the kernel stores them
in the ``activity`` table of the event store's SQLite file when it commits the callback. Storing is
idempotent per callback event, so a retried callback is not logged twice. ``rosaos log`` and
``GET /activity`` read it back, newest last.
"""

from __future__ import annotations

import json
import sqlite3
from collections.abc import Sequence
from typing import Any

from pydantic import BaseModel, ConfigDict, Field

from rosaos.kernel.database import Database
from rosaos.receipts import Receipt, SafetyDecision

DEFAULT_LIMIT = 200
MAX_LIMIT = 2000

_SCHEMA = """
CREATE TABLE IF NOT EXISTS activity (
    id INTEGER PRIMARY KEY AUTOINCREMENT,
    event_id INTEGER,                       -- the worker_callback event that carried the receipt
    seq INTEGER NOT NULL,                   -- its place among that callback's receipts
    process_id INTEGER NOT NULL,
    device TEXT NOT NULL,
    tool TEXT NOT NULL,
    arguments TEXT NOT NULL,
    ok INTEGER NOT NULL,
    result TEXT,
    error TEXT,
    started REAL NOT NULL,
    duration REAL NOT NULL,
    safety TEXT,
    UNIQUE (event_id, seq)
);
CREATE INDEX IF NOT EXISTS activity_started ON activity (started);
"""
_COLUMNS = "id, process_id, device, tool, arguments, ok, result, error, started, duration, safety"


class ActivityEntry(BaseModel):
    """One tool call in the activity log (``GET /activity``)."""

    model_config = ConfigDict(extra="forbid")

    id: int
    process_id: int
    device: str
    tool: str
    arguments: dict[str, Any]
    """Secret arguments are already redacted by the worker."""
    ok: bool
    result: str | None = Field(description="The result as JSON text (cut when long); null on error.")
    error: str | None
    started: float = Field(description="Seconds since the epoch.")
    duration: float = Field(description="Seconds.")
    safety: SafetyDecision | None


class ActivityPage(BaseModel):
    """``GET /activity``: the matching tool calls, oldest first (the newest ``limit`` of them)."""

    entries: list[ActivityEntry]


class ActivityLog:
    """Reads and writes the ``activity`` table. Shares the event store's :class:`Database`."""

    def __init__(self, database: Database) -> None:
        self._database = database

    @classmethod
    async def open(cls, database: Database) -> ActivityLog:
        """Create the ``activity`` table if needed. Pass ``event_store.database``."""
        await database.executescript(_SCHEMA)
        return cls(database)

    async def record(self, event_id: int | None, process_id: int, receipts: Sequence[Receipt]) -> None:
        """Store a callback's receipts; a second call for the same ``event_id`` stores nothing."""
        if not receipts:
            return
        rows = [
            (
                event_id,
                seq,
                process_id,
                receipt.device,
                receipt.tool,
                json.dumps(receipt.arguments),
                int(receipt.ok),
                receipt.result,
                receipt.error,
                receipt.started,
                receipt.duration,
                receipt.safety.model_dump_json() if receipt.safety else None,
            )
            for seq, receipt in enumerate(receipts)
        ]

        def insert(connection: sqlite3.Connection) -> None:
            connection.executemany(
                "INSERT OR IGNORE INTO activity (event_id, seq, process_id, device, tool, arguments, ok,"
                " result, error, started, duration, safety) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                rows,
            )

        await self._database.run(insert)

    async def query(
        self,
        device: str | None = None,
        process_id: int | None = None,
        since: float | None = None,
        limit: int = DEFAULT_LIMIT,
    ) -> list[ActivityEntry]:
        """The newest ``limit`` calls matching the filters, oldest first."""
        where, parameters = [], []
        for clause, value in (
            ("device = ?", device),
            ("process_id = ?", process_id),
            ("started >= ?", since),
        ):
            if value is not None:
                where.append(clause)
                parameters.append(value)
        sql = f"SELECT {_COLUMNS} FROM activity"
        if where:
            sql += " WHERE " + " AND ".join(where)
        sql += " ORDER BY started DESC, id DESC LIMIT ?"
        rows = await self._database.fetch(sql, [*parameters, max(1, min(limit, MAX_LIMIT))])
        return [_entry(row) for row in reversed(rows)]


def _entry(row: tuple[Any, ...]) -> ActivityEntry:
    entry_id, process_id, device, tool, arguments, ok, result, error, started, duration, safety = row
    return ActivityEntry(
        id=entry_id,
        process_id=process_id,
        device=device,
        tool=tool,
        arguments=json.loads(arguments),
        ok=bool(ok),
        result=result,
        error=error,
        started=started,
        duration=duration,
        safety=SafetyDecision.model_validate_json(safety) if safety else None,
    )
