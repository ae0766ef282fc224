"""Synthetic camera frames: a floor, a sky, and four coloured pillars around the origin.

The pillars stand at fixed places in the world, so the picture changes as the robot moves and
turns (a model can tell that it did). Frames are small (160x120) to keep rosbridge traffic light.
"""

from __future__ import annotations

import base64
import io
import math
from typing import Any

from PIL import Image, ImageDraw

from rosaos_ros.messages import header, wrap_angle

WIDTH, HEIGHT = 160, 120
FIELD_OF_VIEW = math.radians(70)
PILLARS = (
    (2.0, 0.0, (220, 40, 40)),
    (0.0, 2.0, (40, 170, 60)),
    (-2.0, 0.0, (40, 80, 220)),
    (0.0, -2.0, (230, 200, 40)),
)
"""(x, y, colour): red ahead of the origin, green to its left, blue behind, yellow to its right."""


def render(x: float, y: float, yaw: float) -> Image.Image:
    """The view from a robot at ``(x, y)`` facing ``yaw`` (radians)."""
    image = Image.new("RGB", (WIDTH, HEIGHT), (150, 190, 230))
    draw = ImageDraw.Draw(image)
    draw.rectangle((0, HEIGHT // 2, WIDTH, HEIGHT), fill=(120, 110, 100))
    visible = []
    for px, py, colour in PILLARS:
        distance = math.hypot(px - x, py - y)
        bearing = wrap_angle(math.atan2(py - y, px - x) - yaw)
        if distance > 0.1 and abs(bearing) < FIELD_OF_VIEW / 2 + 0.2:
            visible.append((distance, bearing, colour))
    for distance, bearing, colour in sorted(visible, reverse=True):  # far ones first
        centre = WIDTH / 2 - bearing / (FIELD_OF_VIEW / 2) * (WIDTH / 2)
        half_width = max(2.0, 12 / distance)
        half_height = min(HEIGHT / 2, 40 / distance)
        draw.rectangle(
            (
                centre - half_width,
                HEIGHT / 2 - half_height,
                centre + half_width,
                HEIGHT / 2 + half_height / 2,
            ),
            fill=colour,
        )
    draw.text((3, 2), f"x={x:.2f} y={y:.2f} yaw={math.degrees(yaw):.0f}", fill=(20, 20, 20))
    return image


def jpeg_bytes(image: Image.Image) -> bytes:
    """``image`` encoded as JPEG."""
    buffer = io.BytesIO()
    image.save(buffer, format="JPEG", quality=80)
    return buffer.getvalue()


def compressed_image_message(image: Image.Image, frame_id: str) -> dict[str, Any]:
    """A ``sensor_msgs/CompressedImage`` (JPEG), data base64-encoded as rosbridge sends ``uint8[]``."""
    return {
        "header": header(frame_id),
        "format": "jpeg",
        "data": base64.b64encode(jpeg_bytes(image)).decode("ascii"),
    }


def raw_image_message(image: Image.Image, frame_id: str) -> dict[str, Any]:
    """A ``sensor_msgs/Image`` in ``rgb8``."""
    return {
        "header": header(frame_id),
        "height": image.height,
        "width": image.width,
        "encoding": "rgb8",
        "is_bigendian": 0,
        "step": image.width * 3,
        "data": base64.b64encode(image.tobytes()).decode("ascii"),
    }
