"""capture_image's picture for a multimodal model: downscaled and bounded in bytes."""

from __future__ import annotations

import io
import random

from PIL import Image

from rosaos_ros.camera import jpeg_for_model


def test_the_picture_is_downscaled_to_the_budget() -> None:
    jpeg = jpeg_for_model(Image.new("RGB", (1280, 720), (40, 120, 200)), 256, 400_000)
    assert Image.open(io.BytesIO(jpeg)).size == (256, 144)


def test_a_noisy_picture_is_squeezed_under_the_byte_bound() -> None:
    noise = Image.frombytes("RGB", (800, 600), random.Random(1).randbytes(800 * 600 * 3))
    jpeg = jpeg_for_model(noise, 800, 50_000)
    assert len(jpeg) <= 50_000 and Image.open(io.BytesIO(jpeg)).format == "JPEG"
