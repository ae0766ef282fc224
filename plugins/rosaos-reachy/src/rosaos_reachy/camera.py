"""Pictures: the robot's camera through the SDK, or a simulated one where there is no media.

The simulated camera looks at a flat scene in front of the robot: the sim's ``camera_image``
(a photo with faces, a room) on a generated backdrop, or only the backdrop. Where the head
points decides which part of the scene is in view, so turning toward a face centres it, as on
the robot. Every simulated frame says so in its corner and in the tool result.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from rosaos.devices.images import scaled_size
from rosaos.drivers import DeviceError
from rosaos_reachy.robot import Posture, RobotLink

FRAME_W, FRAME_H = 640, 480
SIM_HFOV_DEG = 70.0
"""Horizontal field of view of the simulated camera; close to the Reachy Mini's wide lens."""

Image = np.ndarray[Any, Any]


def focal_px(width: int, hfov_deg: float) -> float:
    """Pinhole focal length in pixels for an image ``width`` wide with field of view ``hfov_deg``."""
    return (width / 2.0) / math.tan(math.radians(hfov_deg) / 2.0)


def pixel_to_angles(u: float, v: float, width: int, height: int, fx: float) -> tuple[float, float]:
    """Head (yaw, pitch) change in degrees that brings pixel (u, v) to the image centre.

    Right of centre turns right (negative yaw); below centre tilts down (positive pitch).
    """
    yaw = -math.degrees(math.atan((u - width / 2.0) / fx))
    pitch = math.degrees(math.atan((v - height / 2.0) / fx))
    return yaw, pitch


@dataclass
class SimCamera:
    """A camera looking at a flat scene; the head's yaw and pitch pan the view across it.

    The scene (three frames wide and tall, 8 MiB) is drawn at the first frame, not at start: most
    runs never look through the camera, and the device host would hold it all the while.
    """

    image: Path | None = None
    fx: float = focal_px(FRAME_W, SIM_HFOV_DEG)
    _scene: Image | None = field(default=None, repr=False)

    @classmethod
    def build(cls, image: Path | None) -> SimCamera:
        """The camera for the sim's ``camera_image``; DeviceError now if OpenCV cannot read it."""
        if image is not None and not cv2.haveImageReader(str(image)):
            raise DeviceError(f"sim camera_image {image}: not an image OpenCV can read (JPEG, PNG)")
        return cls(image)

    @property
    def scene(self) -> Image:
        """The generated backdrop, with ``image`` in the middle (drawn once, on first use)."""
        if self._scene is None:
            self._scene = _scene(self.image)
        return self._scene

    def frame(self, posture: Posture) -> Image:
        """What the camera sees with the head at ``posture`` (its yaw and pitch)."""
        yaw = posture.head.yaw
        pitch = posture.head.pitch
        cx = self.scene.shape[1] / 2.0 - self.fx * math.tan(math.radians(max(-60.0, min(60.0, yaw))))
        cy = self.scene.shape[0] / 2.0 + self.fx * math.tan(math.radians(max(-45.0, min(45.0, pitch))))
        left = round(min(max(cx - FRAME_W / 2, 0), self.scene.shape[1] - FRAME_W))
        top = round(min(max(cy - FRAME_H / 2, 0), self.scene.shape[0] - FRAME_H))
        view = self.scene[top : top + FRAME_H, left : left + FRAME_W].copy()
        label = f"SIMULATED CAMERA  yaw {yaw:+.0f}  pitch {pitch:+.0f}"
        cv2.putText(
            view, label, (8, FRAME_H - 10), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1, cv2.LINE_AA
        )
        return view


def _scene(image: Path | None) -> Image:
    scene = _backdrop(FRAME_W * 3, FRAME_H * 3)
    if image is not None:
        picture = cv2.imread(str(image))
        if picture is None:
            raise DeviceError(f"sim camera_image {image}: not an image OpenCV can read (JPEG, PNG)")
        scale = min(FRAME_W / picture.shape[1], FRAME_H / picture.shape[0])
        if scale < 1.0:  # fit the view at yaw 0; smaller pictures keep their size
            picture = cv2.resize(picture, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
        h, w = picture.shape[:2]
        top, left = (scene.shape[0] - h) // 2, (scene.shape[1] - w) // 2
        scene[top : top + h, left : left + w] = picture
    return scene


def _backdrop(width: int, height: int) -> Image:
    """A plain generated room: a graded wall, a floor, a window, a shelf and a plant."""
    ys = np.linspace(0.0, 1.0, height, dtype=np.float32)[:, None]
    wall = (np.array([190, 200, 210], np.float32) * (1.0 - 0.25 * ys))[:, None, :]
    scene = np.broadcast_to(wall, (height, width, 3)).astype(np.uint8).copy()
    horizon = int(height * 0.72)
    scene[horizon:] = (70, 90, 120)  # floor (BGR: a brown-ish wood)
    cv2.rectangle(
        scene,
        (int(width * 0.08), int(height * 0.15)),
        (int(width * 0.28), int(height * 0.45)),
        (235, 215, 170),
        -1,
    )
    cv2.rectangle(
        scene,
        (int(width * 0.08), int(height * 0.15)),
        (int(width * 0.28), int(height * 0.45)),
        (90, 90, 90),
        6,
    )
    cv2.rectangle(
        scene,
        (int(width * 0.70), int(height * 0.40)),
        (int(width * 0.92), int(height * 0.43)),
        (60, 80, 110),
        -1,
    )
    cv2.circle(scene, (int(width * 0.85), int(height * 0.62)), int(height * 0.06), (60, 140, 60), -1)
    for x in range(0, width, 80):  # faint tiles, so panning is visible
        cv2.line(scene, (x, 0), (x, horizon), (175, 185, 195), 1)
    return scene


def grab(robot: RobotLink | None, sim: SimCamera | None, posture: Posture) -> tuple[Image, bool]:
    """A frame from the robot's camera, else from the simulated one: ``(image, simulated)``.

    Blocking (the SDK reads GStreamer): run it in a thread.
    """
    if robot is not None and robot.has_camera:
        for _ in range(20):  # the first frames of a fresh stream can be empty
            frame = robot.frame()
            if frame is not None:
                return frame, False
            time.sleep(0.05)
        raise DeviceError("the robot's camera gave no picture; check the camera in the Reachy Mini app")
    if sim is None:
        raise DeviceError(
            "no camera: the daemon runs without media (--no-media) and this is not a simulation; "
            "set media = true and start the daemon with its camera"
        )
    return sim.frame(posture), True


def save_jpeg(image: Image, folder: Path, stem: str) -> Path:
    """Write ``image`` as JPEG in ``folder`` under a fresh name; returns the path."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{stem}-{time.strftime('%Y%m%d-%H%M%S')}-{int(time.time() * 1000) % 1000:03d}.jpg"
    if not cv2.imwrite(str(path), image, [cv2.IMWRITE_JPEG_QUALITY, 90]):
        raise DeviceError(f"could not write {path}; check that the images directory is writable")
    return path


def jpeg_for_model(image: Image, max_px: int, max_bytes: int) -> bytes:
    """``image`` downscaled so its longer side is at most ``max_px``, as a JPEG of at most
    ``max_bytes`` (lower quality first, then smaller): a bounded picture for a model's context."""
    height, width = image.shape[:2]
    size = scaled_size(width, height, max_px)
    while True:
        resized = image if size == (width, height) else cv2.resize(image, size, interpolation=cv2.INTER_AREA)
        for quality in (80, 65, 50, 35):
            ok, encoded = cv2.imencode(".jpg", resized, [cv2.IMWRITE_JPEG_QUALITY, quality])
            if not ok:
                raise DeviceError("could not encode the picture as JPEG")
            if len(encoded) <= max_bytes or size[0] <= 64:
                return bytes(encoded.tobytes())
        size = (max(1, size[0] * 3 // 4), max(1, size[1] * 3 // 4))
