"""Perception tools: finding people with the robot's camera, on this computer (no cloud, no download)."""

from __future__ import annotations

from typing import Annotated, Any

from fastmcp import FastMCP
from pydantic import Field

from rosaos_ros.backend import RosBackend

LOOKS: dict[str, Any] = {"readOnlyHint": False, "destructiveHint": False, "idempotentHint": False}
"""Takes a picture (a new file) and records what it saw; moves nothing."""


def register(mcp: FastMCP, backend: RosBackend) -> None:
    """Add detect_people."""

    @mcp.tool(annotations=LOOKS)
    async def detect_people(
        timeout: Annotated[
            float, Field(gt=0, le=30, description="Seconds to wait for a camera frame.")
        ] = 5.0,
    ) -> dict[str, Any]:
        """Take a picture and find the people in it, with a detector that runs on this computer.

        Returns found (true or false), count, and for each person: distance_m and bearing_deg
        from the robot (positive bearing: to the left), direction in words, x and y in the
        odometry frame (metres), and the detector's box and score; plus the picture's path and
        the pose it was taken at. People are found standing and facing roughly the camera, from
        about 1.5 m to 6 m; someone closer shows only in part. Sightings also appear in
        get_state's people_seen. To search a room, turn between pictures (or use search).
        """
        return await backend.detect_people(timeout)
