"""What ``describe_image`` says with no vision model: a description computed on this computer.

It counts the people (OpenCV's HOG pedestrian detector) and the faces (the Haar cascade the face
tools use, with remembered names), names the dominant colours (k-means on a small copy of the
picture, each centre named after the nearest of a few plain colours) and says how bright the
picture is. Everything ships inside OpenCV's wheel: no download, no network. It then says that
a vision model would say more, and how to configure one.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache
from typing import Any

import cv2
import numpy as np

NAMED_COLOURS: dict[str, tuple[int, int, int]] = {  # RGB
    "black": (20, 20, 20),
    "dark grey": (80, 80, 80),
    "grey": (128, 128, 128),
    "light grey": (190, 190, 190),
    "white": (240, 240, 240),
    "red": (200, 40, 40),
    "dark red": (120, 20, 20),
    "orange": (235, 140, 40),
    "brown": (120, 80, 45),
    "beige": (215, 195, 160),
    "yellow": (230, 210, 50),
    "green": (50, 160, 60),
    "dark green": (25, 80, 35),
    "light blue": (150, 190, 230),
    "blue": (40, 80, 200),
    "navy": (25, 35, 90),
    "purple": (120, 60, 160),
    "pink": (235, 150, 180),
    "skin tone": (220, 170, 140),
}
VISION_MODEL_HINT = (
    "A vision model would say more (objects, text, what people are doing): set GROQ_API_KEY, or "
    "[devices.<reachy>] vision_base_url for any OpenAI-compatible vision endpoint."
)


@cache
def _hog() -> cv2.HOGDescriptor:
    hog = cv2.HOGDescriptor()
    hog.setSVMDetector(np.array(cv2.HOGDescriptor.getDefaultPeopleDetector(), dtype=np.float32))
    return hog


def count_people(image: np.ndarray[Any, Any]) -> int:
    """Standing people in a BGR picture (whole bodies; a face close up is counted as a face)."""
    scale = 640 / image.shape[1]
    frame = cv2.resize(image, None, fx=scale, fy=scale) if scale != 1 else image
    rects, weights = _hog().detectMultiScale(frame, winStride=(8, 8), scale=1.05)
    boxes = [
        tuple(int(v) for v in rect) for rect, w in zip(rects, np.ravel(weights), strict=True) if w >= 1.0
    ]
    if not boxes:
        return 0
    kept = cv2.dnn.NMSBoxes(boxes, [1.0] * len(boxes), 0.5, 0.3)
    return len(kept)


def dominant_colours(image: np.ndarray[Any, Any], count: int = 3) -> list[tuple[str, float]]:
    """The picture's main colours, named, with their share of the picture (0-1), largest first."""
    small = cv2.resize(image, (64, 48), interpolation=cv2.INTER_AREA).reshape(-1, 3).astype(np.float32)
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 20, 1.0)
    _, labels, centres = cv2.kmeans(small, 5, None, criteria, 3, cv2.KMEANS_PP_CENTERS)  # type: ignore[call-overload]
    shares: dict[str, float] = {}
    for index, centre in enumerate(centres):
        b, g, r = (float(v) for v in centre)
        name = min(
            NAMED_COLOURS,
            key=lambda n: sum((a - c) ** 2 for a, c in zip(NAMED_COLOURS[n], (r, g, b), strict=True)),
        )
        shares[name] = shares.get(name, 0.0) + float(np.mean(labels.ravel() == index))
    return sorted(shares.items(), key=lambda item: -item[1])[:count]


def brightness(image: np.ndarray[Any, Any]) -> float:
    """Mean brightness, 0 (black) to 1 (white)."""
    return float(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY).mean()) / 255.0


def describe_locally(image: np.ndarray[Any, Any], face_names: Sequence[str | None]) -> str:
    """A plain description of a BGR picture; ``face_names`` has one entry per face found (None: unknown)."""
    people = count_people(image)
    faces = len(face_names)
    known = sorted({name for name in face_names if name})
    parts = []
    if faces:
        who = f" ({', '.join(known)})" if known else ""
        parts.append(f"{faces} face{'s' if faces != 1 else ''}{who}")
    if people:
        parts.append(f"{people} standing {'person' if people == 1 else 'people'}")
    seen = " and ".join(parts) if parts else "no one (no face, no standing person)"
    colours = ", ".join(f"{name} ({share:.0%})" for name, share in dominant_colours(image))
    level = brightness(image)
    light = (
        "dark" if level < 0.25 else "dim" if level < 0.45 else "well lit" if level < 0.75 else "very bright"
    )
    return (
        f"Described on this computer, without a vision model: I see {seen}. "
        f"Main colours: {colours}. The picture is {light} (brightness {level:.0%}). {VISION_MODEL_HINT}"
    )
