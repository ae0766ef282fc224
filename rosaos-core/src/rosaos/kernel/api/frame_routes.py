"""Camera frames for the web page: the last picture each device saved, and what was found in it.

Drivers save captures in the shared images directory (``DeviceContext.images_dir``) as
``<instance>-<time>.jpg`` (ROS ``capture_image``, Reachy ``take_picture``). These routes sit on the
protected router, so the same bearer token as the rest of the API is needed; there is no public
path to an image. A file is only ever looked up by listing the directory and matching names, never
by joining a client's text to a path, so ``..`` or a slash cannot reach another file.

The outlines come from the activity log: the newest successful tool call of the device whose result
names the frame and lists boxes (``faces``, ``people``, ``detections`` or ``boxes``, each with
``x``, ``y``, ``width``, ``height`` in pixels, and optionally a ``label`` or ``looks_like``).
"""

from __future__ import annotations

import asyncio
import json
import re
from pathlib import Path
from typing import Annotated, Any

from fastapi import HTTPException, Request
from fastapi import Path as FastPath
from fastapi.responses import FileResponse
from pydantic import BaseModel, Field

from rosaos.kernel.api.routes import Runtime, protected

FRAME_SUFFIXES = (".jpg", ".jpeg", ".png")
BOX_LISTS = ("faces", "people", "detections", "boxes")
RECENT_CALLS = 50
"""How many of the device's newest tool calls are searched for the boxes of a frame."""
FILE_NAME = r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,200}$"


class FrameBox(BaseModel):
    """Something found in a frame, in pixels from the top left."""

    x: float
    y: float
    width: float
    height: float
    label: str | None = None


class FrameInfo(BaseModel):
    """``GET /devices/{name}/frame``: the newest frame of a device and what was found in it."""

    device: str
    file: str | None = Field(
        description="Fetch the image at /devices/{name}/frames/{file} (same token); null: no frame yet."
    )
    time: float | None = Field(
        default=None, description="When the file was written, seconds since the epoch."
    )
    width: int | None = None
    height: int | None = None
    boxes: list[FrameBox] = Field(default_factory=list)
    boxes_from: str | None = Field(default=None, description="The tool whose result gave the boxes.")


def _images_dir(request: Request) -> Path:
    images: Path | None = getattr(request.app.state, "images_dir", None)
    if images is None:
        raise HTTPException(404, "this kernel keeps no camera frames (no images directory configured)")
    return images


async def _known_device(runtime: Runtime, name: str) -> None:
    names = [device.name for device in await runtime.devices()]
    if name not in names:
        raise HTTPException(404, f"no device {name!r}: GET /devices lists them ({', '.join(names)})")


def _frames_of(images: Path, device: str) -> list[Path]:
    """The device's frames, newest first. ``<device>-`` then a digit, so ``dog`` never takes ``dog_2``'s."""
    if not images.is_dir():
        return []
    pattern = re.compile(rf"^{re.escape(device)}-\d.*")
    found = [
        path
        for path in images.iterdir()
        # A symlink could point anywhere on the disk: only regular files the drivers wrote count.
        if pattern.match(path.name)
        and path.suffix.lower() in FRAME_SUFFIXES
        and not path.is_symlink()
        and path.is_file()
    ]
    return sorted(found, key=lambda path: path.stat().st_mtime, reverse=True)


def boxes_in(result: dict[str, Any]) -> list[FrameBox]:
    """The boxes a detection result lists, in any of the shapes drivers use."""
    for key in BOX_LISTS:
        items = result.get(key)
        if not isinstance(items, list):
            continue
        boxes = []
        for item in items:
            if not isinstance(item, dict):
                continue
            width, height = item.get("width", item.get("w")), item.get("height", item.get("h"))
            x, y = item.get("x"), item.get("y")
            if all(isinstance(v, int | float) for v in (x, y, width, height)):
                label = item.get("label") or item.get("looks_like") or item.get("name")
                boxes.append(
                    FrameBox(x=x, y=y, width=width, height=height, label=str(label) if label else None)
                )
        return boxes
    return []


def _names_frame(result: dict[str, Any], file: str) -> bool:
    return any(
        isinstance(result.get(key), str) and Path(result[key]).name == file for key in ("path", "image")
    )


async def _details(runtime: Runtime, device: str, file: str) -> FrameInfo:
    info = FrameInfo(device=device, file=file)
    for entry in reversed(await runtime.activity.query(device=device, limit=RECENT_CALLS)):
        if not entry.ok or not entry.result:
            continue
        try:
            result = json.loads(entry.result)
        except ValueError:  # cut at the receipt limit: not readable, look further back
            continue
        if not isinstance(result, dict) or not _names_frame(result, file):
            continue
        if info.width is None and isinstance(result.get("width"), int):
            info.width, info.height = result["width"], result.get("height")
        if not info.boxes_from and any(isinstance(result.get(key), list) for key in BOX_LISTS):
            info.boxes, info.boxes_from = boxes_in(result), entry.tool
    return info


@protected.get("/devices/{name}/frame", responses={404: {"description": "No such device"}})
async def latest_frame(
    name: Annotated[str, FastPath(max_length=100)], request: Request, runtime: Runtime
) -> FrameInfo:
    """The newest camera frame this device saved, with the people or faces found in it.

    A device that has not saved one yet answers ``file: null`` (not 404: it is a normal state)."""
    await _known_device(runtime, name)
    frames = await asyncio.to_thread(_frames_of, _images_dir(request), name)
    if not frames:
        return FrameInfo(device=name, file=None)
    newest = frames[0]
    info = await _details(runtime, name, newest.name)
    info.time = newest.stat().st_mtime
    return info


@protected.get(
    "/devices/{name}/frames/{file}",
    response_class=FileResponse,
    responses={200: {"content": {"image/jpeg": {}, "image/png": {}}}, 404: {"description": "No such frame"}},
)
async def frame_file(
    name: Annotated[str, FastPath(max_length=100)],
    file: Annotated[str, FastPath(pattern=FILE_NAME)],
    request: Request,
    runtime: Runtime,
) -> FileResponse:
    """One saved frame of this device, by the file name ``GET /devices/{name}/frame`` gave."""
    await _known_device(runtime, name)
    # Only a name found by listing the directory is served: never a path built from the request.
    frames = {path.name: path for path in await asyncio.to_thread(_frames_of, _images_dir(request), name)}
    if file not in frames:
        raise HTTPException(404, f"{name} has no frame {file!r}; GET /devices/{name}/frame names the newest")
    return FileResponse(frames[file], headers={"Cache-Control": "private, max-age=3600"})
