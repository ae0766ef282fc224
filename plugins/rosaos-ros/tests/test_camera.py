"""capture_image: a frame from the camera topic, decoded, saved as JPEG, returned by relative path."""

from __future__ import annotations

import base64
from pathlib import Path
from typing import Any

import pytest
from PIL import Image

from rosaos.drivers import DeviceError
from rosaos_ros.camera import decode
from rosaos_ros.messages import IMAGE


async def test_capture_image_saves_a_jpeg_from_the_compressed_topic(open_robot: Any, tmp_path: Path) -> None:
    async with open_robot() as robot:
        result = await robot.call("capture_image")
    saved = tmp_path / "images" / result["image"]
    assert result["image"].startswith("turtlebot-") and result["image"].endswith(".jpg")
    assert result["topic"] == "/oakd/rgb/preview/image_raw/compressed"
    with Image.open(saved) as image:
        assert (image.format, image.size) == ("JPEG", (320, 240))


async def test_capture_image_decodes_a_raw_topic_too(open_robot: Any, tmp_path: Path) -> None:
    async with open_robot(camera_topic="/oakd/rgb/preview/image_raw") as robot:
        result = await robot.call("capture_image")
    with Image.open(tmp_path / "images" / result["image"]) as image:
        assert image.format == "JPEG"


async def test_a_profile_without_camera_says_how_to_set_one(open_robot: Any) -> None:
    async with open_robot(profile="generic", sim={}) as robot:
        error = await robot.error("capture_image")
    assert "camera_topic" in error


@pytest.mark.parametrize(
    ("encoding", "pixel", "expected"),
    [
        ("rgb8", b"\x10\x20\x30", (16, 32, 48)),
        ("bgr8", b"\x10\x20\x30", (48, 32, 16)),
        ("mono8", b"\x40", (64, 64, 64)),
    ],
)
def test_raw_encodings_decode_to_rgb(encoding: str, pixel: bytes, expected: tuple[int, int, int]) -> None:
    msg = {
        "width": 2,
        "height": 1,
        "encoding": encoding,
        "step": 2 * len(pixel),
        "data": base64.b64encode(pixel * 2).decode(),
    }
    assert decode(IMAGE, msg).getpixel((1, 0)) == expected


def test_mono16_keeps_the_high_byte() -> None:
    msg = {
        "width": 1,
        "height": 1,
        "encoding": "mono16",
        "is_bigendian": 0,
        "step": 2,
        "data": list(b"\x34\x12"),
    }
    assert decode(IMAGE, msg).getpixel((0, 0)) == (0x12, 0x12, 0x12)


def test_an_unsupported_encoding_is_a_clear_error() -> None:
    with pytest.raises(DeviceError, match="unsupported encoding 'yuv422'"):
        decode(IMAGE, {"width": 1, "height": 1, "encoding": "yuv422", "data": "AAAA"})
