"""What rosaOS remembers, for the page's floor map: ``GET /places`` and ``GET /sightings``.

Registered on the protected router of :mod:`rosaos.kernel.api.routes` (the bearer token applies).
Places are saved by saying so to the kernel (``POST /chat``) or with ``rosaos places``; the page
renames and deletes them here (``PATCH`` and ``DELETE /places/{name}``), with the same rules as
``rosaos places rename`` and ``delete``: an unknown place is 404, a name another place has is 409,
an empty or too long name 422. Sightings come from the robots' cameras, and "forget what you saw"
clears them; ``GET /sightings/{id}/picture`` serves the picture of one ("show me"), only ever a
picture file inside the images folder, whatever name a device's result gave. Each place and
sighting keeps the frame its coordinates are in and the device whose frame that is, so the page
can draw it where that device's own pose is drawn (its ``map_origin``).
"""

from __future__ import annotations

import asyncio
import time
from typing import Annotated

from fastapi import HTTPException, Query, Request
from fastapi import Path as FastPath
from fastapi.responses import FileResponse
from pydantic import BaseModel, ConfigDict, Field

from rosaos.kernel.api.routes import Runtime, protected
from rosaos.memory.sightings import Sighting, picture_path
from rosaos.memory.store import (
    NAME_MAX,
    MemoryRequestError,
    Place,
    PlaceNameTakenError,
    UnknownPlaceError,
)

PlaceName = Annotated[
    str, FastPath(min_length=1, max_length=NAME_MAX, description="The place's name, any case.")
]


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


class PlaceRename(BaseModel):
    """``PATCH /places/{name}``: the place's new name."""

    model_config = ConfigDict(extra="forbid")

    name: str = Field(min_length=1, max_length=NAME_MAX, description="The new name, e.g. 'the kitchen'.")


def _refusal(error: MemoryRequestError) -> HTTPException:
    if isinstance(error, UnknownPlaceError):
        return HTTPException(404, str(error))
    if isinstance(error, PlaceNameTakenError):
        return HTTPException(409, str(error))
    return HTTPException(422, str(error))


@protected.patch(
    "/places/{name}",
    responses={404: {"description": "No such place"}, 409: {"description": "Another place has the new name"}},
)
async def rename_place(name: PlaceName, rename: PlaceRename, runtime: Runtime) -> Place:
    """Rename a place; its pose and frame stay. Answers the renamed place."""
    try:
        return runtime.memory.rename_place(name, rename.name)
    except MemoryRequestError as error:
        raise _refusal(error) from None


@protected.delete("/places/{name}", responses={404: {"description": "No such place"}})
async def delete_place(name: PlaceName, runtime: Runtime) -> Place:
    """Delete a place. Answers the place that was deleted (say so again to save it back)."""
    try:
        return runtime.memory.forget_place(name)
    except MemoryRequestError as error:
        raise _refusal(error) from None


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


@protected.get(
    "/sightings/{sighting_id}/picture",
    response_class=FileResponse,
    responses={
        200: {"content": {"image/jpeg": {}, "image/png": {}}},
        404: {"description": "No such picture"},
    },
)
async def sighting_picture(
    sighting_id: Annotated[
        int,
        FastPath(
            ge=1, le=2**63 - 1, description="The sighting's id, from GET /sightings (SQLite's integer range)."
        ),
    ],
    request: Request,
    runtime: Runtime,
) -> FileResponse:
    """The picture a sighting was made from ("show me"): a JPEG or PNG from the images folder."""
    sighting = runtime.sightings.get(sighting_id)
    if sighting is None:
        raise HTTPException(
            404,
            f"no sighting {sighting_id}: it was forgotten or is older than the keep window; GET /sightings lists them",
        )
    images = getattr(request.app.state, "images_dir", None)
    path = None
    if images is not None and sighting.image is not None:
        path = await asyncio.to_thread(picture_path, images, sighting.image)
    if path is None:
        raise HTTPException(
            404, f"sighting {sighting_id} has no picture on this machine (none was taken, or it was deleted)"
        )
    return FileResponse(path, headers={"Cache-Control": "private, max-age=3600"})
