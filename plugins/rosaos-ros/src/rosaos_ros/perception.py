"""Finding people in camera frames with what ships inside OpenCV's wheel: no download, no cloud.

Two detectors read the pixels, and their boxes are merged:

- OpenCV's HOG pedestrian detector (``HOGDescriptor.getDefaultPeopleDetector``, a linear SVM
  on histograms of oriented gradients, trained on whole standing people). It finds people from
  about 1.5 m to 6 m in a 320x240 frame.
- The frontal-face Haar cascade (``cv2.data.haarcascades``), which still finds a face turned to
  the camera when the body is cut by the frame's edge.

A frame is scaled to :data:`WORK_WIDTH` first: small frames up (the HOG window is 64x128, so a
far person in a small frame is otherwise too small), large ones down (the time stays bounded).
Both run at a few hundred milliseconds a frame on one core; call :func:`find_people` in a thread.

:func:`place` turns a box into where the person is: the bearing from the box's column and the
camera's field of view, the range from its height (an adult is about :data:`PERSON_HEIGHT` tall,
and the HOG box is 128/96 of the person it holds), and world coordinates from the robot's pose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from PIL.Image import Image as PILImage

WORK_WIDTH = 640
"""Pixels: every frame is scaled to this width before detection."""
HOG_MIN_SCORE = 1.0
"""SVM margin below which a HOG window is not a person (weak hits come from edges and text)."""
OVERLAP = 0.3
"""Boxes overlapping more than this (intersection over union) are one person."""
PERSON_HEIGHT = 1.7
"""Metres: the height assumed for the range estimate."""
HOG_BOX_RATIO = 128 / 96
"""A HOG box is this much taller than the person in it (the 64x128 window holds a 96 px person)."""
FACE_WIDTH = 0.22
"""Metres: the width of the face cascade's box on an adult face, for the range estimate."""


@dataclass(frozen=True)
class PersonBox:
    """One person found in a frame, in the frame's own pixels."""

    left: int
    top: int
    width: int
    height: int
    score: float
    """HOG: the SVM margin (above 1; 2 or more is sure); face: the cascade's neighbour count."""
    method: str
    """``body`` (HOG) or ``face`` (Haar cascade)."""


@dataclass(frozen=True)
class Placement:
    """Where a person is relative to the camera, and in the world when the pose is known."""

    bearing: float
    """Radians, positive to the left of the optical axis (REP-103)."""
    distance: float
    """Metres from the camera, estimated from the box's size."""
    x: float | None = None
    y: float | None = None


@cache
def _hog() -> cv2.HOGDescriptor:
    hog = cv2.HOGDescriptor()
    hog.setSVMDetector(np.array(cv2.HOGDescriptor.getDefaultPeopleDetector(), dtype=np.float32))
    return hog


@cache
def _faces() -> cv2.CascadeClassifier:
    path = Path(cv2.data.haarcascades) / "haarcascade_frontalface_default.xml"  # type: ignore[attr-defined]
    cascade = cv2.CascadeClassifier(str(path))
    if cascade.empty():
        raise RuntimeError(f"OpenCV's face cascade is missing at {path}; reinstall opencv-python-headless")
    return cascade


def find_people(image: PILImage) -> list[PersonBox]:
    """Every person in ``image``, most certain first. Blocking (CPU): run it in a thread."""
    frame = cv2.cvtColor(np.asarray(image.convert("RGB")), cv2.COLOR_RGB2BGR)
    scale = WORK_WIDTH / frame.shape[1]
    if scale != 1:
        interpolation = cv2.INTER_LINEAR if scale > 1 else cv2.INTER_AREA
        frame = cv2.resize(frame, None, fx=scale, fy=scale, interpolation=interpolation)
    boxes = _bodies(frame) + _face_boxes(frame)
    kept = _merge(boxes)
    return [
        PersonBox(
            round(box.left / scale),
            round(box.top / scale),
            round(box.width / scale),
            round(box.height / scale),
            box.score,
            box.method,
        )
        for box in kept
    ]


def _bodies(frame: np.ndarray[Any, Any]) -> list[PersonBox]:
    # A border lets the window reach people standing at the frame's edge or filling its height.
    pad = 32
    padded = cv2.copyMakeBorder(frame, pad, pad, pad, pad, cv2.BORDER_REPLICATE)
    rects, weights = _hog().detectMultiScale(padded, winStride=(8, 8), scale=1.05)
    found = []
    for (left, top, width, height), weight in zip(rects, np.ravel(weights), strict=True):
        if float(weight) >= HOG_MIN_SCORE:
            found.append(
                PersonBox(
                    int(left) - pad, int(top) - pad, int(width), int(height), round(float(weight), 2), "body"
                )
            )
    return found


def _face_boxes(frame: np.ndarray[Any, Any]) -> list[PersonBox]:
    gray = cv2.equalizeHist(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY))
    rects, _, levels = _faces().detectMultiScale3(
        gray, scaleFactor=1.1, minNeighbors=5, minSize=(32, 32), outputRejectLevels=True
    )
    return [
        PersonBox(int(left), int(top), int(width), int(height), round(float(level), 2), "face")
        for (left, top, width, height), level in zip(rects, np.ravel(levels), strict=True)
    ]


def _merge(boxes: list[PersonBox]) -> list[PersonBox]:
    """One box per person: bodies first (their size gives a better range), then faces of no body."""
    kept: list[PersonBox] = []
    for box in sorted(boxes, key=lambda b: (b.method != "body", -b.score)):
        if not any(_overlap(box, other) > OVERLAP or _inside(box, other) for other in kept):
            kept.append(box)
    return kept


def _overlap(a: PersonBox, b: PersonBox) -> float:
    width = min(a.left + a.width, b.left + b.width) - max(a.left, b.left)
    height = min(a.top + a.height, b.top + b.height) - max(a.top, b.top)
    if width <= 0 or height <= 0:
        return 0.0
    shared = width * height
    return shared / (a.width * a.height + b.width * b.height - shared)


def _inside(inner: PersonBox, outer: PersonBox) -> bool:
    cx, cy = inner.left + inner.width / 2, inner.top + inner.height / 2
    return outer.left <= cx <= outer.left + outer.width and outer.top <= cy <= outer.top + outer.height


def place(
    box: PersonBox, image_width: int, fov: float, pose: tuple[float, float, float] | None = None
) -> Placement:
    """Where the person in ``box`` is: bearing and range from the camera; world x, y given the robot's
    ``pose`` (x, y, yaw), with the camera on the robot's axis looking straight ahead.

    ``fov`` is the camera's horizontal field of view in radians.
    """
    focal = (image_width / 2) / math.tan(fov / 2)
    column = box.left + box.width / 2
    bearing = math.atan2(image_width / 2 - column, focal)
    if box.method == "body":
        depth = focal * PERSON_HEIGHT / (box.height / HOG_BOX_RATIO)
    else:
        depth = focal * FACE_WIDTH / box.width
    distance = min(20.0, depth / math.cos(bearing))
    if pose is None:
        return Placement(bearing, distance)
    x, y, yaw = pose
    return Placement(
        bearing, distance, x + distance * math.cos(yaw + bearing), y + distance * math.sin(yaw + bearing)
    )
