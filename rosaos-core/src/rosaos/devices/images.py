"""Pictures for multimodal models: whether the calling process's model takes images, and how big.

The worker knows its model (pydantic-ai's ``supports_image_input`` profile flag, or
``[models] vision``). It tells each device in one HTTP header on its MCP session,
:data:`IMAGES_HEADER`, whose value is the longest side in pixels the model should get. A camera
tool reads it with :func:`image_budget`: ``None`` means a text-only model (return the path only),
a number means downscale to it and add the JPEG as MCP image content with
:func:`picture_result`.
"""

from __future__ import annotations

import base64
import json
from typing import Any

from fastmcp.server.dependencies import get_http_headers
from fastmcp.tools.base import ToolResult
from mcp.types import ImageContent, TextContent

IMAGES_HEADER = "x-rosaos-images"
"""Set by the worker when its model accepts images: the longest image side, in pixels."""
DEFAULT_IMAGE_MAX_PX = 768
MIN_IMAGE_PX, MAX_IMAGE_PX = 64, 4096
MAX_IMAGE_BYTES = 400_000
"""A picture's JPEG is re-encoded at lower quality until it fits (a few hundred tokens' worth)."""


def image_budget() -> int | None:
    """The longest side (px) the calling model takes, or ``None`` for a text-only model.

    Outside an HTTP request (in-memory clients, tests of the tool alone) it is ``None``.
    """
    value = get_http_headers(include={IMAGES_HEADER}).get(IMAGES_HEADER)
    if not value:
        return None
    try:
        return max(MIN_IMAGE_PX, min(MAX_IMAGE_PX, int(value)))
    except ValueError:
        return None


def scaled_size(width: int, height: int, max_px: int) -> tuple[int, int]:
    """``(width, height)`` scaled down (never up) so the longer side is at most ``max_px``."""
    longest = max(width, height)
    if longest <= max_px:
        return width, height
    return max(1, round(width * max_px / longest)), max(1, round(height * max_px / longest))


def picture_result(report: dict[str, Any], jpeg: bytes) -> ToolResult:
    """The result of a camera tool for a model that takes images: the report plus the picture.

    The report (path, size, ...) stays the structured content, so a front end and the activity
    log read the same fields whatever the model; a text-only model gets the report alone.
    """
    picture = ImageContent(type="image", data=base64.b64encode(jpeg).decode(), mime_type="image/jpeg")
    shown = {**report, "image_sent": True}
    return ToolResult(
        content=[TextContent(type="text", text=json.dumps(shown)), picture], structured_content=shown
    )
