"""What rosaOS remembers, in SQLite in the data directory: named places, and what people told it.

One file, ``memory.db``, owner-only like the rest of the data directory, next to the event store
(a separate file, so ``rosaos memory clear`` never touches the queue). Two tables:

- **places**: a name, the pose (x, y, yaw) and the frame it is in: the frame's name (``map``,
  ``odom``) and its anchor (which map, which odometry session; see the ROS driver's ``get_pose``).
  A place is only ever given back with its anchor, so a robot in another frame refuses it.
- **notes**: what people said, by kind: ``fact`` ("my name is Sam"), ``alias`` ("call the dog
  Rex": ``rex`` means ``the dog``) and ``preference``. Keyed by (kind, key); saying it again
  replaces it.
- **sightings**: what the robots saw (:mod:`rosaos.memory.sightings`).

The calls are synchronous: each is one small local transaction (well under a millisecond), and
both the kernel and the CLI use the file, the CLI while the kernel runs (WAL mode).
"""

from __future__ import annotations

import re
import sqlite3
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any, Literal, TypeVar

from pydantic import BaseModel, ConfigDict, Field

T = TypeVar("T")

MEMORY_FILE = "memory.db"
NAME_MAX = 80
NoteKind = Literal["fact", "alias", "preference"]
_ARTICLES = re.compile(r"^(?:the|my|our|a|an)\s+", re.IGNORECASE)

_SCHEMA = """
CREATE TABLE IF NOT EXISTS places (
    key TEXT PRIMARY KEY,
    name TEXT NOT NULL,
    device TEXT NOT NULL,
    frame TEXT NOT NULL,
    anchor TEXT NOT NULL,
    x REAL NOT NULL,
    y REAL NOT NULL,
    yaw REAL,
    saved_at REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS notes (
    kind TEXT NOT NULL,
    key TEXT NOT NULL,
    value TEXT NOT NULL,
    said TEXT NOT NULL,
    saved_at REAL NOT NULL,
    PRIMARY KEY (kind, key)
);
CREATE TABLE IF NOT EXISTS sightings (
    id INTEGER PRIMARY KEY,
    what TEXT NOT NULL,
    device TEXT NOT NULL,
    at REAL NOT NULL,
    x REAL,
    y REAL,
    frame TEXT,
    anchor TEXT,
    place TEXT,
    image TEXT
);
"""


class MemoryRequestError(ValueError):
    """A request memory cannot carry out; the message says why and what to do instead."""


class UnknownPlaceError(MemoryRequestError):
    """No place has that name (the HTTP API answers 404)."""


class PlaceNameTakenError(MemoryRequestError):
    """Another place already has that name (the HTTP API answers 409)."""


def place_key(name: str) -> str:
    """The key a place is found by: lowercase, single spaces, no leading article ("the Kitchen" → "kitchen")."""
    words = " ".join(name.lower().replace("_", " ").split())
    return _ARTICLES.sub("", words).strip(" .,!?'\"")


class Place(BaseModel):
    """A named pose in one frame."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: Annotated[str, Field(min_length=1, max_length=NAME_MAX)]
    device: str
    """The robot that saved it (it goes there by default)."""
    frame: str
    anchor: str
    x: Annotated[float, Field(allow_inf_nan=False)]
    y: Annotated[float, Field(allow_inf_nan=False)]
    yaw: Annotated[float | None, Field(allow_inf_nan=False)] = None
    saved_at: float

    @property
    def key(self) -> str:
        return place_key(self.name)


class Note(BaseModel):
    """One thing a person told rosaOS."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    kind: NoteKind
    key: str
    value: str
    said: str
    """The sentence, as said: what ``what do you remember?`` reads back."""
    saved_at: float


class MemoryStore:
    """The memory file of one data directory."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._local = threading.local()
        self._writes = 0
        """Bumped by this store's own writes of notes and places, which its connection's
        ``data_version`` does not see (see :meth:`_kept`)."""
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        fresh = not path.exists()
        with self.connect() as db:
            db.execute("PRAGMA journal_mode=WAL")
            db.executescript(_SCHEMA)
        if fresh:
            path.chmod(0o600)

    @classmethod
    def open(cls, data_dir: Path) -> MemoryStore:
        """The store in ``data_dir`` (created on first use)."""
        return cls(data_dir / MEMORY_FILE)

    @contextmanager
    def connect(self) -> Iterator[sqlite3.Connection]:
        """This thread's connection, in a transaction. It stays open: the kernel reads the memory
        on every event (aliases, the summary in its prompt), and opening the file each time cost
        more than the reads, on the event loop, for every command of a burst."""
        db: sqlite3.Connection | None = getattr(self._local, "db", None)
        if db is None:
            db = sqlite3.connect(self.path, timeout=5)
            db.row_factory = sqlite3.Row
            self._local.db = db
        with db:
            yield db

    # Places

    def save_place(self, place: Place) -> Place:
        """Store ``place``, replacing one of the same name."""
        if not place.key:
            raise MemoryRequestError("a place needs a name, e.g. 'the kitchen'")
        with self.connect() as db:
            db.execute(
                "INSERT OR REPLACE INTO places VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (place.key, place.name, place.device, place.frame, place.anchor, place.x, place.y, place.yaw,
                 place.saved_at),
            )  # fmt: skip
        self._writes += 1
        return place

    def place(self, name: str) -> Place | None:
        """The place called ``name`` (any case, with or without "the"), or None."""
        with self.connect() as db:
            row = db.execute("SELECT * FROM places WHERE key = ?", (place_key(name),)).fetchone()
        return _place(row) if row is not None else None

    def places(self) -> list[Place]:
        """Every place, by name (kept until a write: :meth:`_kept`)."""
        return self._kept("places", "SELECT * FROM places ORDER BY key", (), _place)

    def rename_place(self, name: str, new_name: str) -> Place:
        """Rename a place; refuses a name already taken."""
        place = self.require_place(name)
        if not place_key(new_name):
            raise MemoryRequestError("the new name is empty; give the place a name, e.g. 'the kitchen'")
        if len(new_name.strip()) > NAME_MAX:
            raise MemoryRequestError(
                f"the new name is {len(new_name.strip())} characters; at most {NAME_MAX}"
            )
        if place_key(new_name) != place.key and self.place(new_name) is not None:
            raise PlaceNameTakenError(
                f"there is already a place called {new_name!r}; forget it first or pick another name"
            )
        renamed = place.model_copy(update={"name": new_name.strip()})
        with self.connect() as db:
            db.execute("DELETE FROM places WHERE key = ?", (place.key,))
        return self.save_place(renamed)

    def forget_place(self, name: str) -> Place:
        """Delete a place; :class:`MemoryRequestError` names the known places when there is none."""
        place = self.require_place(name)
        with self.connect() as db:
            db.execute("DELETE FROM places WHERE key = ?", (place.key,))
        self._writes += 1
        return place

    def require_place(self, name: str) -> Place:
        """The place called ``name``; :class:`MemoryRequestError` naming the known ones otherwise."""
        place = self.place(name)
        if place is None:
            known = ", ".join(p.name for p in self.places()) or "none yet"
            raise UnknownPlaceError(
                f"I don't know a place called {name!r} (known places: {known}); "
                f"stand the robot there and say 'remember this spot as {name}'"
            )
        return place

    # Notes

    def save_note(self, kind: NoteKind, key: str, value: str, said: str) -> Note:
        """Store a note, replacing one of the same kind and key."""
        key = " ".join(key.lower().split())
        if not key or not value.strip():
            raise MemoryRequestError("there is nothing to remember in that")
        note = Note(kind=kind, key=key, value=value.strip(), said=said.strip(), saved_at=time.time())
        with self.connect() as db:
            db.execute(
                "INSERT OR REPLACE INTO notes VALUES (?, ?, ?, ?, ?)",
                (note.kind, note.key, note.value, note.said, note.saved_at),
            )
        self._writes += 1
        return note

    def notes(self, kind: NoteKind | None = None) -> list[Note]:
        """Every note (or every one of ``kind``), oldest first (kept until a write: :meth:`_kept`)."""
        if kind is None:
            return self._kept("notes", "SELECT * FROM notes ORDER BY saved_at", (), _note)
        return self._kept(
            f"notes {kind}", "SELECT * FROM notes WHERE kind = ? ORDER BY saved_at", (kind,), _note
        )

    def _kept(
        self, key: str, query: str, args: tuple[str, ...], build: Callable[[sqlite3.Row], T]
    ) -> list[T]:
        """The rows of ``query``, built, from this thread's last reading if nothing was written since.

        The kernel reads the notes and places on every event (aliases at the stop reading and in
        the engine, the summary in its instructions), and they change only when someone says to
        remember or forget. A write by this store bumps its counter; one by another connection
        (another thread, ``rosaos memory`` in another process) changes SQLite's
        ``PRAGMA data_version`` on this one. Either way the next read goes to the file.
        """
        with self.connect() as db:
            version = (self._writes, db.execute("PRAGMA data_version").fetchone()[0])
            kept: dict[str, tuple[tuple[int, int], list[Any]]] = self._local.__dict__.setdefault("kept", {})
            last = kept.get(key)
            if last is not None and last[0] == version:
                return list(last[1])
            rows = [build(row) for row in db.execute(query, args)]
        kept[key] = (version, rows)
        return list(rows)

    def forget_notes(self, matching: str) -> list[Note]:
        """Delete the notes whose key, value or sentence contains every word of ``matching``."""
        words = matching.lower().split()
        gone = [
            note
            for note in self.notes()
            if words and all(word in f"{note.key} {note.value} {note.said}".lower() for word in words)
        ]
        with self.connect() as db:
            for note in gone:
                db.execute("DELETE FROM notes WHERE kind = ? AND key = ?", (note.kind, note.key))
        self._writes += 1
        return gone

    def aliases(self) -> dict[str, str]:
        """Alias → what it names ("rex" → "the dog")."""
        return {note.key: note.value for note in self.notes("alias")}

    def preferences(self) -> dict[str, str]:
        """What the user likes a thing at ("my reading light" → "40 percent")."""
        return {note.key: note.value for note in self.notes("preference")}

    def clear(self) -> tuple[int, int]:
        """Forget everything (sightings too); returns how many places and notes were deleted."""
        with self.connect() as db:
            places = db.execute("DELETE FROM places").rowcount
            notes = db.execute("DELETE FROM notes").rowcount
            db.execute("DELETE FROM sightings")
        self._writes += 1
        return places, notes


def _note(row: sqlite3.Row) -> Note:
    return Note(**dict(row))


def _place(row: sqlite3.Row) -> Place:
    data = dict(row)
    data.pop("key")
    return Place(**data)
