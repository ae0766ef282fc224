"""Camera captures: one frame from an image topic, decoded and saved as a JPEG file.

Both ``sensor_msgs/Image`` (``rgb8``, ``bgr8``, ``rgba8``, ``bgra8``, ``mono8``, ``mono16``) and
``sensor_msgs/CompressedImage`` (JPEG or PNG) are understood. The tool returns the file's path
relative to the shared images directory; when the calling model accepts images it also gets a
downscaled JPEG (:func:`jpeg_for_model`).
"""

from __future__ import annotations

import base64
import io
import re
import time
from pathlib import Path
from typing import Any

from PIL import Image, UnidentifiedImageError

from rosaos.devices.images import scaled_size
from rosaos.drivers import DeviceError
from rosaos_ros.messages import COMPRESSED_IMAGE, IMAGE, normalize_type

RAW_MODES = {
    "rgb8": ("RGB", "RGB"),
    "bgr8": ("RGB", "BGR"),
    "rgba8": ("RGBA", "RGBA"),
    "bgra8": ("RGBA", "BGRA"),
    "mono8": ("L", "L"),
}
_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]+")


def decode(msg_type: str, msg: dict[str, Any]) -> Image.Image:
    """The picture in an Image or CompressedImage message; :class:`DeviceError` if it cannot be read."""
    kind = normalize_type(msg_type)
    try:
        data = _bytes(msg.get("data"))
        if kind == COMPRESSED_IMAGE:
            return Image.open(io.BytesIO(data)).convert("RGB")
        if kind == IMAGE:
            return _raw(msg, data)
    except (UnidentifiedImageError, ValueError, OSError) as error:
        raise DeviceError(f"the camera sent a frame that cannot be decoded: {error}") from None
    raise DeviceError(f"{msg_type} is not an image type; use a sensor_msgs/Image or CompressedImage topic")


def _bytes(data: Any) -> bytes:
    if isinstance(data, str):  # rosbridge sends uint8[] as base64
        return base64.b64decode(data)
    if isinstance(data, list):
        return bytes(data)
    raise ValueError("the message has no image data")


def _raw(msg: dict[str, Any], data: bytes) -> Image.Image:
    width, height, step = int(msg["width"]), int(msg["height"]), int(msg.get("step") or 0)
    encoding = str(msg.get("encoding", "")).lower()
    if encoding == "mono16":  # keep each pixel's high byte: a depth or IR image, viewable
        step = step or width * 2
        high = 0 if msg.get("is_bigendian") else 1
        body = b"".join(data[row * step : row * step + width * 2][high::2] for row in range(height))
        return Image.frombytes("L", (width, height), body).convert("RGB")
    if encoding not in RAW_MODES:
        raise ValueError(f"unsupported encoding {encoding!r}; supported: {', '.join([*RAW_MODES, 'mono16'])}")
    mode, raw_mode = RAW_MODES[encoding]
    return Image.frombytes(mode, (width, height), data, "raw", raw_mode, step).convert("RGB")


def save_jpeg(image: Image.Image, images_dir: Path, instance: str) -> Path:
    """Save ``image`` as ``<images_dir>/<instance>-<time>.jpg``; returns the path relative to ``images_dir``."""
    images_dir.mkdir(parents=True, exist_ok=True)
    stamp = time.strftime("%Y%m%d-%H%M%S") + f"-{int(time.time() * 1000) % 1000:03d}"
    relative = Path(f"{_UNSAFE.sub('_', instance)}-{stamp}.jpg")
    image.save(images_dir / relative, format="JPEG", quality=85)
    return relative


def jpeg_for_model(image: Image.Image, max_px: int, max_bytes: int) -> bytes:
    """``image`` downscaled so its longer side is at most ``max_px``, as a JPEG of at most ``max_bytes``
    (lower quality first, then smaller, so a model's context gets a bounded picture)."""
    frame = image.convert("RGB")
    size = scaled_size(frame.width, frame.height, max_px)
    while True:
        resized = frame.resize(size) if size != frame.size else frame
        for quality in (80, 65, 50, 35):
            buffer = io.BytesIO()
            resized.save(buffer, format="JPEG", quality=quality)
            if buffer.tell() <= max_bytes or size[0] <= 64:
                return buffer.getvalue()
        size = (max(1, size[0] * 3 // 4), max(1, size[1] * 3 // 4))
