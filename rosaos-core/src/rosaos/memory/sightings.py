"""What the robots saw: every person a robot's camera found, with when, where and the picture.

The kernel records sightings from the receipts of a process's tool calls (the activity log's
source), when the process's callback is recorded: a ``detect_people`` result (each person with
x, y in the robot's frame, and the picture) and a ``search`` that found someone. Nothing polls.
A sighting keeps its frame, and the nearest named place is looked up among the places of the
same frame anchor only (a place on another map says nothing about where this was).

A Reachy's ``detect_faces`` is recorded too, one ``face`` per face found. Its x, y are pixels in
the picture, not a position: a Reachy does not drive, so the face was where the Reachy stands.
That spot is the device's ``map_origin`` on the shared floor map (``[devices.NAME]`` in
``rosaos.toml``): the sighting is at (0, 0) in the ``fixed`` frame of that device, and its nearest
place is the nearest named place on the floor map, each place placed by its own robot's
``map_origin`` as the page draws it. Without a ``map_origin`` the face has no position.

Sightings are kept ``[memory] sightings_days`` days (default :data:`KEEP_DAYS`), and "forget
what you saw" clears them.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict

from rosaos.memory.store import MemoryStore, Place
from rosaos.receipts import Receipt

KEEP_DAYS = 7.0
NEAR_PLACE = 3.0
"""Metres: a sighting further than this from every place is "near no named place"."""
PICTURE_SUFFIXES = (".jpg", ".jpeg", ".png")
FIXED = "fixed"
"""The frame of a device that does not move (a Reachy): (0, 0) is where it stands, its map_origin."""
Origin = tuple[float, float, float]
"""A device's ``map_origin``: x, y (metres) and yaw (radians) of its own frame on the floor map."""


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

    def __init__(
        self,
        store: MemoryStore,
        keep_days: float = KEEP_DAYS,
        origins: Mapping[str, Origin] | None = None,
        images_dir: Path | None = None,
    ) -> None:
        self.store = store
        self.keep_days = keep_days
        self.origins = dict(origins or {})
        """Each device's ``map_origin``: where a Reachy's faces were, and places on the floor map."""
        self.images_dir = images_dir
        """Where the drivers save pictures (the data directory's ``images``); None: not known here."""

    def record_receipts(self, receipts: Iterable[Receipt]) -> list[Sighting]:
        """Record the people found by the tool calls in ``receipts``; returns the new sightings."""
        found = [s for receipt in receipts if receipt.ok for s in _sightings(receipt)]
        ids: list[int] = []
        places = self.store.places()
        placed = [self._placed(s, places) for s in found]
        with self.store.connect() as db:
            for s in placed:
                cursor = db.execute(
                    "INSERT INTO sightings (what, device, at, x, y, frame, anchor, place, image) "
                    "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?)",
                    (s.what, s.device, s.at, s.x, s.y, s.frame, s.anchor, s.place, s.image),
                )
                ids.append(int(cursor.lastrowid or 0))
            db.execute("DELETE FROM sightings WHERE at < ?", (time.time() - self.keep_days * 86400,))
        return [s.model_copy(update={"id": id_}) for s, id_ in zip(placed, ids, strict=True)]

    def _placed(self, sighting: Sighting, places: list[Place]) -> Sighting:
        if sighting.frame != FIXED:
            return sighting.model_copy(update={"place": _nearest(sighting, places)})
        origin = self.origins.get(sighting.device)
        if origin is None:  # nowhere on the floor map: kept, with its picture, but not placed
            return sighting
        return sighting.model_copy(update={"x": 0.0, "y": 0.0, "place": self._nearest_on_map(origin, places)})

    def _nearest_on_map(self, spot: Origin, places: list[Place]) -> str | None:
        """The named place nearest ``spot`` on the floor map, each place moved by its robot's origin."""
        on_map = [(_on_map(self.origins.get(p.device), p.x, p.y), p.name) for p in places]
        ranked = sorted((math.hypot(x - spot[0], y - spot[1]), name) for (x, y), name in on_map)
        return ranked[0][1] if ranked and ranked[0][0] <= NEAR_PLACE else None

    def get(self, sighting_id: int) -> Sighting | None:
        """One sighting by its id (within the keep window), or None."""
        since = time.time() - self.keep_days * 86400
        with self.store.connect() as db:
            row = db.execute(
                "SELECT * FROM sightings WHERE id = ? AND at >= ?", (sighting_id, since)
            ).fetchone()
        return Sighting(**dict(row)) if row is not None else None

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

    def with_picture(self) -> Sighting | None:
        """The newest sighting whose picture is on this machine ("show me"), or None."""
        return next((s for s in self.recent(limit=50) if self.picture(s) is not None), None)

    def picture(self, sighting: Sighting) -> Path | None:
        """The file of ``sighting``'s picture in :attr:`images_dir`, or None (none, or deleted)."""
        if self.images_dir is None or sighting.image is None:
            return None
        return picture_path(self.images_dir, sighting.image)

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
    if receipt.tool.endswith("detect_faces"):
        faces = [face for face in result.get("faces") or [] if isinstance(face, dict)]
        image = result.get("path") if isinstance(result.get("path"), str) else None
        return [Sighting(what="face", device=receipt.device, at=at, frame=FIXED, image=image) for _ in faces]
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


def picture_path(images_dir: Path, image: str) -> Path | None:
    """``image`` (relative to ``images_dir``) as a file inside it, or None.

    The name comes from a device's tool result, so it is checked as untrusted: a picture suffix,
    no way out of the folder (``..``, an absolute path, a symlink), and a regular file."""
    if not image.lower().endswith(PICTURE_SUFFIXES) or Path(image).is_absolute():
        return None
    root = images_dir.resolve()
    path = images_dir / image
    if path.is_symlink() or not path.is_file() or root not in path.resolve().parents:
        return None
    return path


def _on_map(origin: Origin | None, x: float, y: float) -> tuple[float, float]:
    """``(x, y)`` of a device's own frame on the floor map (what the page's ``toMap`` does)."""
    if origin is None:
        return x, y
    ox, oy, yaw = origin
    return ox + math.cos(yaw) * x - math.sin(yaw) * y, oy + math.sin(yaw) * x + math.cos(yaw) * y


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
