"""State and camera tools."""

from __future__ import annotations

import asyncio
from typing import Annotated, Any

from fastmcp import FastMCP
from fastmcp.tools.base import ToolResult
from pydantic import Field

from rosaos.devices.images import MAX_IMAGE_BYTES, image_budget, picture_result
from rosaos.drivers import CHANGES
from rosaos_ros import camera
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

    @mcp.tool(annotations=CHANGES)
    async def capture_image(
        timeout: Annotated[float, Field(gt=0, le=30, description="Seconds to wait for a frame.")] = 5.0,
    ) -> dict[str, Any] | ToolResult:
        """Take a picture with the robot's camera and save it as a JPEG file.

        Returns the file's path relative to the rosaOS images directory, with its size; pass the
        path on to whoever needs to see it. If you can see images, the picture comes with it.
        """
        max_px = image_budget()
        report, image = await backend.capture_frame(timeout)
        if max_px is None:
            # A text-only model gets the path; detect_people says who is in the picture.
            return report
        jpeg = await asyncio.to_thread(camera.jpeg_for_model, image, max_px, MAX_IMAGE_BYTES)
        return picture_result(report, jpeg)
