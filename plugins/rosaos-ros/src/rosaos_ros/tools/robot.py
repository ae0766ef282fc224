"""State and camera tools."""

from __future__ import annotations

from typing import Annotated, Any

from fastmcp import FastMCP
from pydantic import Field

from rosaos_ros.backend import RosBackend
from rosaos_ros.tools import READ_ONLY


def register(mcp: FastMCP, backend: RosBackend) -> None:
    """Add get_state and capture_image."""
    extra = ", ".join(backend.profile.state) or "no other keys"

    async def get_state() -> dict[str, Any]:
        return await backend.get_state()

    mcp.tool(
        get_state,
        description=(
            "Read the robot: x, y in metres and yaw in radians (positive: turned left) from odometry, "
            "linear (m/s) and angular (rad/s) velocities, the profile name, and the profile's own keys "
            f"({extra})."
        ),
        annotations=READ_ONLY,
    )

    @mcp.tool(annotations={"readOnlyHint": False, "destructiveHint": False, "idempotentHint": False})
    async def capture_image(
        timeout: Annotated[float, Field(gt=0, le=30, description="Seconds to wait for a frame.")] = 5.0,
    ) -> dict[str, Any]:
        """Take a picture with the robot's camera and save it as a JPEG file.

        Returns the file's path relative to the rosaOS images directory (never the image itself),
        with its size; pass the path on to whoever needs to see it.
        """
        return await backend.capture_image(timeout)
