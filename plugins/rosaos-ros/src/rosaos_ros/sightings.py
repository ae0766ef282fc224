"""People a robot has seen: what ``detect_people`` found, placed in the world, kept for ``get_state``.

``get_state`` carries ``people_seen: [{x, y, at}]`` (odometry frame, metres, newest last, at most
:data:`KEEP`) once someone was seen, so the web page can mark them on the floor map.
"""

from __future__ import annotations

import asyncio
import math
from collections import deque
from datetime import UTC, datetime
from typing import Any

from PIL.Image import Image as PILImage

from rosaos_ros.perception import PersonBox, find_people, place

KEEP = 20
"""Sightings kept in ``people_seen``."""


class Sightings:
    """The robot's recent sightings of people, in world coordinates."""

    def __init__(self, fov_degrees: float) -> None:
        self.fov = math.radians(fov_degrees)
        self.seen: deque[dict[str, Any]] = deque(maxlen=KEEP)

    async def detect(self, image: PILImage, pose: tuple[float, float, float] | None) -> list[dict[str, Any]]:
        """Find the people in ``image`` (a frame taken at ``pose``: x, y, yaw), record them, describe each."""
        boxes = await asyncio.to_thread(find_people, image)
        return [self._describe(box, image.width, pose) for box in boxes]

    def _describe(
        self, box: PersonBox, width: int, pose: tuple[float, float, float] | None
    ) -> dict[str, Any]:
        where = place(box, width, self.fov, pose)
        bearing = math.degrees(where.bearing)
        side = "ahead" if abs(bearing) < 5 else ("to the left" if bearing > 0 else "to the right")
        person: dict[str, Any] = {
            "distance_m": round(where.distance, 2),
            "bearing_deg": round(bearing, 1),
            "direction": side,
            "method": box.method,
            "score": box.score,
            "box": [box.left, box.top, box.width, box.height],
        }
        if where.x is not None and where.y is not None:
            person |= {"x": round(where.x, 2), "y": round(where.y, 2)}
            self.seen.append(
                {"x": person["x"], "y": person["y"], "at": datetime.now(UTC).isoformat(timespec="seconds")}
            )
        return person

    def state(self) -> dict[str, Any]:
        """The ``get_state`` keys: ``people_seen`` once anyone was seen, else nothing."""
        return {"people_seen": list(self.seen)} if self.seen else {}
