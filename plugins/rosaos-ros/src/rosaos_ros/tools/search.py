"""The long-task tool: ``search`` for a person, with progress as it goes."""

from __future__ import annotations

import logging
from typing import Annotated, Any

from fastmcp import Context, FastMCP
from pydantic import Field

from rosaos_ros.backend import RosBackend
from rosaos_ros.tools import MOVES

log = logging.getLogger("rosaos_ros.search")
TARGETS = {"person", "people", "someone", "somebody", "anyone", "anybody", "human"}


def register(mcp: FastMCP, backend: RosBackend) -> None:
    """Add search, on profiles that can move and see (odometry and a camera)."""
    if backend.profile.odom is None or (
        backend.profile.camera is None and backend.settings.camera_topic is None
    ):
        return

    @mcp.tool(annotations=MOVES)
    async def search(
        ctx: Context,
        target: Annotated[
            str, Field(min_length=1, max_length=40, description="What to look for; only people for now.")
        ] = "person",
        max_seconds: Annotated[
            float | None,
            Field(
                ge=5,
                le=600,
                description="Give up after this many seconds; default: the robot's search_seconds "
                "setting (120 unless set).",
            ),
        ] = None,
        max_distance_m: Annotated[
            float,
            Field(
                ge=0,
                le=10,
                description="Never go further than this from where the search starts; 0 turns in place.",
            ),
        ] = 3.0,
    ) -> dict[str, Any]:
        """Search the surroundings for a person: turn in place taking pictures, then move to nearby spots.

        Stops as soon as someone is found and returns found true with their x, y (odometry frame,
        metres), distance_m and bearing_deg from the robot. Returns found false when nobody was
        found within max_seconds and max_distance_m. Takes up to max_seconds; progress is reported
        as it goes. Respects the velocity limits; stop or the emergency stop end it.
        """
        if target.strip().lower() not in TARGETS:
            raise ValueError(f"search finds people only, not {target!r}; use target='person'")

        limit = backend.settings.search_seconds if max_seconds is None else max_seconds

        async def progress(elapsed: float, message: str) -> None:
            await ctx.report_progress(progress=round(elapsed, 1), total=limit, message=message)

        async def alive() -> bool:
            request = ctx.request_context.request if ctx.request_context else None
            is_disconnected = getattr(request, "is_disconnected", None)
            return not (is_disconnected is not None and await is_disconnected())

        result = await backend.search(limit, max_distance_m, progress, alive)
        await ctx.report_progress(progress=limit, total=limit, message=result["outcome"])
        return result
