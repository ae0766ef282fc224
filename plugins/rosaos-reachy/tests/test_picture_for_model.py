"""take_picture's picture for a multimodal model: downscaled and bounded in bytes."""

from __future__ import annotations

import cv2
import numpy as np

from rosaos_reachy.camera import jpeg_for_model


def test_the_picture_is_downscaled_to_the_budget() -> None:
    frame = np.full((720, 1280, 3), (40, 120, 200), dtype=np.uint8)
    jpeg = jpeg_for_model(frame, 256, 400_000)
    decoded = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
    assert decoded.shape[:2] == (144, 256)


def test_a_noisy_picture_is_squeezed_under_the_byte_bound() -> None:
    noise = np.random.default_rng(1).integers(0, 255, (720, 1280, 3), dtype=np.uint8)
    jpeg = jpeg_for_model(noise, 1024, 60_000)
    assert len(jpeg) <= 60_000 and jpeg[:2] == b"\xff\xd8"
