"""Faces, offline: OpenCV's bundled Haar cascades find them; a small memory tells them apart.

Detection uses ``haarcascade_frontalface_default.xml`` (eyes and smiles: their own cascades), as
shipped inside ``opencv-python-headless``. Remembering a face stores its crop under
``<data>/drivers/reachy/faces/<name>/`` with a descriptor: histograms of local binary patterns
on a 4x4 grid (the classic LBPH recipe). That recognises the same person in similar light and
pose; it is no biometric system, and the answers say "looks like", not "is".
"""

from __future__ import annotations

import json
import re
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from pydantic import BaseModel

from rosaos.drivers import DeviceError

Image = np.ndarray[Any, Any]
FACE_SIZE = 96
GRID = 4
MATCH_DISTANCE = 0.25
"""Chi-square distance under which two faces look alike. Measured here: the same face rescaled,
darkened or mirrored 0.07-0.18; non-faces and noise 0.39 and more."""
_NAME = re.compile(r"^[\w][\w .'-]{0,39}$")


class Face(BaseModel):
    """One detected face: its box in pixels, and who it looks like if remembered."""

    x: int
    y: int
    width: int
    height: int
    center: tuple[float, float]
    """Box centre in [-1, 1] image coordinates: (-1, -1) top left, (1, 1) bottom right."""
    looks_like: str | None = None
    similarity: float | None = None


class FaceAnalysis(Face):
    """``analyze_face``: the largest face, with the cues Haar cascades can give."""

    eyes_visible: int
    smiling: bool
    brightness: float
    """Mean brightness of the face, 0 (black) to 1 (white): under 0.25 the light is poor."""
    size: float
    """Face width as a fraction of the image width: near 0.3 is close to the camera."""


def _cascade(name: str) -> cv2.CascadeClassifier:
    path = Path(cv2.data.haarcascades) / name  # type: ignore[attr-defined]
    cascade = cv2.CascadeClassifier(str(path))
    if cascade.empty():
        raise DeviceError(
            f"OpenCV's {name} is missing ({path}); install opencv-python-headless 4.x, which ships the Haar cascades"
        )
    return cascade


@dataclass
class FaceDetector:
    """The three Haar cascades, loaded once."""

    faces: cv2.CascadeClassifier
    eyes: cv2.CascadeClassifier
    smiles: cv2.CascadeClassifier

    @classmethod
    def load(cls) -> FaceDetector:
        return cls(
            _cascade("haarcascade_frontalface_default.xml"),
            _cascade("haarcascade_eye.xml"),
            _cascade("haarcascade_smile.xml"),
        )

    def detect(self, image: Image) -> list[tuple[int, int, int, int]]:
        """Face boxes ``(x, y, w, h)``, largest first."""
        # No histogram equalisation here: it makes sharp edges (a photo's border, window frames)
        # look face-like; minNeighbors=7 trades a little recall for far fewer false faces.
        gray = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
        side = max(24, min(gray.shape[:2]) // 12)
        boxes = self.faces.detectMultiScale(gray, scaleFactor=1.1, minNeighbors=7, minSize=(side, side))
        return sorted(((int(x), int(y), int(w), int(h)) for x, y, w, h in boxes), key=lambda b: -b[2] * b[3])

    def analyze(self, image: Image, box: tuple[int, int, int, int]) -> tuple[int, bool, float]:
        """(eyes found, smiling, brightness 0-1) for the face in ``box``."""
        x, y, w, h = box
        gray = cv2.cvtColor(image[y : y + h, x : x + w], cv2.COLOR_BGR2GRAY)
        brightness = float(gray.mean()) / 255.0
        gray = cv2.equalizeHist(gray)
        upper, lower = gray[: h // 2], gray[h // 2 :]
        eyes = self.eyes.detectMultiScale(upper, 1.1, 6, minSize=(max(8, w // 10),) * 2)
        smiles = self.smiles.detectMultiScale(lower, 1.5, 18, minSize=(max(12, w // 5), max(8, h // 10)))
        return min(len(eyes), 2), len(smiles) > 0, round(brightness, 2)


def descriptor(image: Image, box: tuple[int, int, int, int]) -> Image:
    """LBP histograms of the face on a 4x4 grid, each normalised: a vector of 16 x 256."""
    x, y, w, h = box
    face = cv2.resize(cv2.cvtColor(image[y : y + h, x : x + w], cv2.COLOR_BGR2GRAY), (FACE_SIZE, FACE_SIZE))
    face = cv2.equalizeHist(face).astype(np.int16)
    center = face[1:-1, 1:-1]
    codes = np.zeros_like(center, dtype=np.uint8)
    offsets = [(-1, -1), (-1, 0), (-1, 1), (0, 1), (1, 1), (1, 0), (1, -1), (0, -1)]
    for bit, (dy, dx) in enumerate(offsets):
        neighbour = face[1 + dy : face.shape[0] - 1 + dy, 1 + dx : face.shape[1] - 1 + dx]
        codes |= (neighbour >= center).astype(np.uint8) << bit
    cell = codes.shape[0] // GRID
    histograms = []
    for row in range(GRID):
        for col in range(GRID):
            block = codes[row * cell : (row + 1) * cell, col * cell : (col + 1) * cell]
            hist = np.bincount(block.ravel(), minlength=256).astype(np.float32)
            histograms.append(hist / max(hist.sum(), 1.0))
    return np.concatenate(histograms)


def distance(a: Image, b: Image) -> float:
    """Mean chi-square distance between two descriptors: 0 for identical faces."""
    return float(0.5 * np.sum((a - b) ** 2 / (a + b + 1e-9)) / (GRID * GRID))


class FaceMemory:
    """Remembered faces on disk: ``<folder>/<name>/<n>.png`` plus ``descriptors.npy`` per name."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self._cache: dict[str, Image] | None = None

    def names(self) -> list[str]:
        return sorted(self._load())

    def remember(self, name: str, image: Image, box: tuple[int, int, int, int]) -> int:
        """Store this face under ``name``; returns how many samples the name now has."""
        if not _NAME.match(name):
            raise DeviceError(f"invalid name {name!r}: use letters, digits, spaces, . ' - (at most 40)")
        person = self.folder / name
        person.mkdir(parents=True, exist_ok=True)
        x, y, w, h = box
        cv2.imwrite(str(person / f"{int(time.time() * 1000)}.png"), image[y : y + h, x : x + w])
        vectors = self._load().get(name)
        new = descriptor(image, box)[None, :]
        vectors = new if vectors is None else np.vstack([vectors, new])
        np.save(person / "descriptors.npy", vectors)
        (person / "person.json").write_text(json.dumps({"name": name, "samples": len(vectors)}))
        self._load()[name] = vectors
        return len(vectors)

    def forget(self, name: str) -> bool:
        """Delete everything stored for ``name``; False if there was nothing."""
        person = self.folder / name
        if name not in self._load() or not person.is_dir():
            return False
        for file in person.iterdir():
            file.unlink()
        person.rmdir()
        self._load().pop(name, None)
        return True

    def match(self, image: Image, box: tuple[int, int, int, int]) -> tuple[str | None, float | None]:
        """The remembered name this face looks most like, and a similarity 0-1; (None, None) if nobody."""
        known = self._load()
        if not known:
            return None, None
        probe = descriptor(image, box)
        best, best_distance = None, float("inf")
        for name, vectors in known.items():
            d = min(distance(probe, v) for v in vectors)
            if d < best_distance:
                best, best_distance = name, d
        similarity = round(max(0.0, 1.0 - best_distance), 2)
        return (best, similarity) if best_distance <= MATCH_DISTANCE else (None, similarity)

    def _load(self) -> dict[str, Image]:
        if self._cache is None:
            self._cache = {}
            if self.folder.is_dir():
                for file in sorted(self.folder.glob("*/descriptors.npy")):
                    self._cache[file.parent.name] = np.load(file)
        return self._cache


def face_from_box(image: Image, box: tuple[int, int, int, int]) -> dict[str, Any]:
    """The box fields of :class:`Face`, with its centre in [-1, 1] image coordinates."""
    x, y, w, h = box
    height, width = image.shape[:2]
    center = (round((x + w / 2) / width * 2 - 1, 3), round((y + h / 2) / height * 2 - 1, 3))
    return {"x": x, "y": y, "width": w, "height": h, "center": center}
