"""What rosaOS remembers, for the page's floor map: ``GET /places`` and ``GET /sightings``.

Registered on the protected router of :mod:`rosaos.kernel.api.routes` (the bearer token applies).
Read-only: places are saved, renamed and forgotten by saying so to the kernel (``POST /chat``) or
with ``rosaos places``; sightings come from the robots' cameras, and "forget what you saw" clears
them. Each place and sighting keeps the frame its coordinates are in and the device whose frame
that is, so the page can draw it where that device's own pose is drawn (its ``map_origin``).
"""

from __future__ import annotations

import time
from typing import Annotated

from fastapi import Query
from pydantic import BaseModel, Field

from rosaos.kernel.api.routes import Runtime, protected
from rosaos.memory.sightings import Sighting
from rosaos.memory.store import Place


class PlaceList(BaseModel):
    """The named places, by name."""

    places: list[Place]


class SightingList(BaseModel):
    """Recent sightings, newest first, with the clock they are measured against."""

    sightings: list[Sighting]
    now: float = Field(description="The kernel's clock (epoch seconds): a sighting's age is now - at.")
    keep_days: float = Field(description="Days a sighting is kept ([memory] sightings_days).")


@protected.get("/places")
async def list_places(runtime: Runtime) -> PlaceList:
    """The named places robots can go to, each in the frame it was saved in."""
    return PlaceList(places=runtime.memory.places())


@protected.get("/sightings")
async def list_sightings(
    runtime: Runtime,
    limit: Annotated[int, Query(ge=1, le=500, description="At most this many, newest first.")] = 100,
) -> SightingList:
    """What the robots saw (people), newest first, within the keep window."""
    return SightingList(
        sightings=runtime.sightings.recent(limit=limit),
        now=time.time(),
        keep_days=runtime.sightings.keep_days,
    )
