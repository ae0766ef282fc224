"""The kernel's SQLite database: one connection in WAL mode, on its own thread.

:class:`Database` runs every statement of the event store (:mod:`rosaos.kernel.event_store`)
on one single-worker executor; the schema and the queries are the store's.
"""

from __future__ import annotations

import asyncio
import sqlite3
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T")


class StoreClosedError(RuntimeError):
    """The store was used after :meth:`Database.close`."""


class Database:
    """One SQLite connection in WAL mode, used only from its own thread.

    Measured on the dev box: a commit takes 17 µs inline, 53 µs through a thread (p50), but a WAL
    checkpoint takes ~3.5 ms, and far more on a robot's SD card. So every statement runs on one
    single-worker executor: the event loop never blocks on disk, statements run in order, and the
    connection needs no lock because only that thread touches it.
    """

    def __init__(self, connection: sqlite3.Connection, executor: ThreadPoolExecutor) -> None:
        self._connection = connection
        self._executor = executor
        self._closed = False

    @classmethod
    async def open(cls, path: Path) -> Database:
        """Open (or create) the SQLite file at ``path``, creating its directory if needed."""
        executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="rosaos-sqlite")
        loop = asyncio.get_running_loop()
        try:
            connection = await loop.run_in_executor(executor, _connect, path)
        except BaseException:
            executor.shutdown(wait=False)
            raise
        return cls(connection, executor)

    async def run(self, work: Callable[[sqlite3.Connection], T]) -> T:
        """Run ``work(connection)`` in one transaction on the database thread; commit before returning."""

        def transaction() -> T:
            self._connection.execute("BEGIN IMMEDIATE")
            try:
                result = work(self._connection)
            except BaseException:
                self._connection.execute("ROLLBACK")
                raise
            self._connection.execute("COMMIT")
            return result

        return await self._submit(transaction)

    async def fetch(self, sql: str, parameters: Sequence[Any] = ()) -> list[tuple[Any, ...]]:
        """Run one read-only statement and return all its rows."""
        return await self._submit(lambda: self._connection.execute(sql, parameters).fetchall())

    async def execute(self, sql: str, parameters: Sequence[Any] = ()) -> None:
        """Run and commit one writing statement."""
        await self.run(lambda connection: connection.execute(sql, parameters).fetchall())

    async def executescript(self, script: str) -> None:
        """Run a schema script (``CREATE ... IF NOT EXISTS``)."""
        await self._submit(lambda: self._connection.executescript(script))

    async def close(self) -> None:
        """Close the connection; later calls raise :class:`StoreClosedError`."""
        if self._closed:
            return
        self._closed = True
        await asyncio.get_running_loop().run_in_executor(self._executor, self._connection.close)
        self._executor.shutdown(wait=False)

    async def _submit(self, work: Callable[[], T]) -> T:
        if self._closed:
            raise StoreClosedError("the kernel event store is closed; open it again with EventStore.open")
        return await asyncio.get_running_loop().run_in_executor(self._executor, work)


def _connect(path: Path) -> sqlite3.Connection:
    path.parent.mkdir(parents=True, exist_ok=True)
    # isolation_level=None: no implicit transactions; Database.run opens them explicitly.
    # check_same_thread=False only because the connection is made and closed through the executor,
    # whose single thread is the only one that ever touches it.
    connection = sqlite3.connect(path, isolation_level=None, check_same_thread=False, timeout=10.0)
    connection.execute("PRAGMA journal_mode=WAL")
    # NORMAL in WAL mode: a commit is durable once it returns as far as a process crash (SIGKILL)
    # goes; on power loss or an OS crash the last few commits before the next checkpoint may be
    # lost (never corrupted). FULL would fsync on every commit: ~100x slower on an SD card.
    connection.execute("PRAGMA synchronous=NORMAL")
    connection.execute("PRAGMA foreign_keys=ON")
    return connection
