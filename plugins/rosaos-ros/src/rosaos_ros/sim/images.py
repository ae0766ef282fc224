"""Synthetic camera frames: a pinhole camera over a floor, four coloured pillars, and any people.

The pillars stand at fixed places in the world and the people where the sim settings put them
(``people: [{x, y}]``), so the picture changes as the robot moves and turns, and a person is in
the frame exactly when a real camera at the robot's pose would see one: within the horizontal
field of view, in front of the lens, nearer things hiding farther ones. Sizes follow the pinhole
model (a thing twice as far is half as tall), so a detector's box tells the range.

The camera sits :data:`CAMERA_HEIGHT` above the floor, tilted up by :data:`CAMERA_PITCH` as
robot cameras are mounted to see people, not only the floor. Frames are 320x240 JPEGs, a few
tens of kilobytes, to keep rosbridge traffic light.
"""

from __future__ import annotations

import base64
import io
import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from PIL import Image, ImageDraw

from rosaos_ros.messages import header, wrap_angle
from rosaos_ros.sim.person import PERSON_HEIGHT, PERSON_WIDTH, person_image

WIDTH, HEIGHT = 320, 240
FIELD_OF_VIEW = math.radians(70)
"""Horizontal field of view (an OAK-D's colour camera has 69 degrees)."""
FOCAL = (WIDTH / 2) / math.tan(FIELD_OF_VIEW / 2)
"""Focal length in pixels, the same horizontally and vertically (square pixels)."""
CAMERA_HEIGHT = 0.3
"""Metres above the floor (a TurtleBot 4's camera)."""
CAMERA_PITCH = math.radians(8)
"""Upward tilt of the camera."""
NEAREST = 0.15
"""Metres: anything nearer the lens than this is not drawn (it would fill the frame)."""
PILLAR_HEIGHT, PILLAR_WIDTH = 1.0, 0.2
PILLARS = (
    (2.0, 0.0, (220, 40, 40)),
    (0.0, 2.0, (40, 170, 60)),
    (-2.0, 0.0, (40, 80, 220)),
    (0.0, -2.0, (230, 200, 40)),
)
"""(x, y, colour): red ahead of the origin, green to its left, blue behind, yellow to its right."""
WALL, FLOOR = (196, 200, 204), (122, 112, 102)


@dataclass(frozen=True)
class _InView:
    depth: float  # metres along the optical axis
    column: float  # pixel column of the thing's centre
    kind: str
    colour: tuple[int, int, int] = (0, 0, 0)


def row_of(height: float, depth: float) -> float:
    """The image row of a point ``height`` metres above the floor, ``depth`` metres ahead of the lens."""
    elevation = math.atan2(height - CAMERA_HEIGHT, depth) - CAMERA_PITCH
    return HEIGHT / 2 - FOCAL * math.tan(elevation)


def render(x: float, y: float, yaw: float, people: Iterable[tuple[float, float]] = ()) -> Image.Image:
    """The view from a robot at ``(x, y)`` facing ``yaw`` (radians), with people standing at ``people``."""
    image = Image.new("RGB", (WIDTH, HEIGHT), WALL)
    draw = ImageDraw.Draw(image)
    horizon = HEIGHT / 2 + FOCAL * math.tan(CAMERA_PITCH)
    draw.rectangle((0, round(horizon), WIDTH, HEIGHT), fill=FLOOR)
    things = [(px, py, "pillar", colour) for px, py, colour in PILLARS]
    things += [(px, py, "person", (0, 0, 0)) for px, py in people]
    visible = []
    for px, py, kind, colour in things:
        bearing = wrap_angle(math.atan2(py - y, px - x) - yaw)
        depth = math.hypot(px - x, py - y) * math.cos(bearing)
        if depth < NEAREST or abs(bearing) >= math.pi / 2:
            continue  # behind the lens
        column = WIDTH / 2 - FOCAL * math.tan(bearing)
        visible.append(_InView(depth, column, kind, colour))
    for thing in sorted(visible, key=lambda t: -t.depth):  # far ones first: near ones hide them
        if thing.kind == "person":
            _draw_person(image, thing)
        else:
            half = FOCAL * PILLAR_WIDTH / 2 / thing.depth
            top, bottom = row_of(PILLAR_HEIGHT, thing.depth), row_of(0.0, thing.depth)
            draw.rectangle((thing.column - half, top, thing.column + half, bottom), fill=thing.colour)
    return image


def _draw_person(image: Image.Image, thing: _InView) -> None:
    top, bottom = row_of(PERSON_HEIGHT, thing.depth), row_of(0.0, thing.depth)
    half = FOCAL * PERSON_WIDTH / 2 / thing.depth
    if thing.column + half < 0 or thing.column - half > WIDTH or bottom < 0 or top > HEIGHT:
        return  # outside the frame, though in front of the lens
    figure = person_image(round(bottom - top))
    image.paste(figure, (round(thing.column - figure.width / 2), round(top)), figure)


def jpeg_bytes(image: Image.Image) -> bytes:
    """``image`` encoded as JPEG."""
    buffer = io.BytesIO()
    image.save(buffer, format="JPEG", quality=85)
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
