"""What the robots saw: every person a robot's camera found, with when, where and the picture.

The kernel records sightings from the receipts of a process's tool calls (the activity log's
source), when the process's callback is recorded: a ``detect_people`` result (each person with
x, y in the robot's frame, and the picture) and a ``search`` that found someone. Nothing polls.
A sighting keeps its frame, and the nearest named place is looked up among the places of the
same frame anchor only (a place on another map says nothing about where this was).

Sightings are kept ``[memory] sightings_days`` days (default :data:`KEEP_DAYS`), and "forget
what you saw" clears them.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Iterable
from typing import Any

from pydantic import BaseModel, ConfigDict

from rosaos.memory.store import MemoryStore, Place
from rosaos.receipts import Receipt

KEEP_DAYS = 7.0
NEAR_PLACE = 3.0
"""Metres: a sighting further than this from every place is "near no named place"."""


class Sighting(BaseModel):
    """One thing (a person) one robot saw."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    id: int = 0
    what: str
    device: str
    at: float
    x: float | None = None
    y: float | None = None
    frame: str | None = None
    anchor: str | None = None
    place: str | None = None
    """The nearest named place in the same frame, within :data:`NEAR_PLACE` m."""
    image: str | None = None
    """The picture, relative to the data directory's images folder."""


class SightingLog:
    """The sightings table of a memory store."""

    def __init__(self, store: MemoryStore, keep_days: float = KEEP_DAYS) -> None:
        self.store = store
        self.keep_days = keep_days

    def record_receipts(self, receipts: Iterable[Receipt]) -> list[Sighting]:
        """Record the people found by the tool calls in ``receipts``; returns the new sightings."""
        found = [s for receipt in receipts if receipt.ok for s in _sightings(receipt)]
        places = self.store.places()
        placed = [s.model_copy(update={"place": _nearest(s, places)}) for s in found]
        with self.store.connect() as db:
            for s in placed:
                db.execute(
                    "INSERT INTO sightings (what, device, at, x, y, frame, anchor, place, image) "
                    "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                    (s.what, s.device, s.at, s.x, s.y, s.frame, s.anchor, s.place, s.image),
                )
            db.execute("DELETE FROM sightings WHERE at < ?", (time.time() - self.keep_days * 86400,))
        return placed

    def recent(self, place: str | None = None, since: float | None = None, limit: int = 20) -> list[Sighting]:
        """Sightings newest first, optionally near ``place`` (its name) and after ``since`` (epoch s)."""
        query = "SELECT * FROM sightings WHERE at >= ?"
        args: list[Any] = [since or time.time() - self.keep_days * 86400]
        if place is not None:
            query += " AND place = ?"
            args.append(place)
        with self.store.connect() as db:
            rows = db.execute(query + " ORDER BY at DESC LIMIT ?", (*args, limit)).fetchall()
        return [Sighting(**dict(row)) for row in rows]

    def clear(self) -> int:
        """Forget every sighting; returns how many."""
        with self.store.connect() as db:
            return int(db.execute("DELETE FROM sightings").rowcount)


def _sightings(receipt: Receipt) -> list[Sighting]:
    """The people a ``detect_people`` or ``search`` result found."""
    try:
        result: Any = json.loads(receipt.result or "")
    except json.JSONDecodeError:
        return []  # cut at the receipt's limit: not readable as a whole
    if not isinstance(result, dict):
        return []
    at = receipt.started + receipt.duration
    if receipt.tool.endswith("detect_people"):
        people = [p for p in result.get("people") or [] if isinstance(p, dict)]
    elif receipt.tool.endswith("search") and result.get("found"):
        people = [result]
    else:
        return []
    return [
        Sighting(
            what="person",
            device=receipt.device,
            at=at,
            x=person.get("x"),
            y=person.get("y"),
            frame=person.get("frame"),
            anchor=person.get("anchor"),
            image=result.get("image"),
        )
        for person in people
    ]


def _nearest(sighting: Sighting, places: list[Place]) -> str | None:
    x, y = sighting.x, sighting.y
    if x is None or y is None or sighting.anchor is None:
        return None
    same = [p for p in places if p.anchor == sighting.anchor]
    if not same:
        return None
    distance, name = min((math.hypot(p.x - x, p.y - y), p.name) for p in same)
    return name if distance <= NEAR_PLACE else None


def ago(at: float, now: float | None = None) -> str:
    """How long ago, for people: "just now", "4 minutes ago", "2 hours ago", "3 days ago"."""
    seconds = max(0.0, (now or time.time()) - at)
    for unit, size in (("day", 86400), ("hour", 3600), ("minute", 60)):
        if seconds >= size:
            count = int(seconds // size)
            return f"{count} {unit}{'s' if count != 1 else ''} ago"
    return "just now"
