"""The vision tools of a Reachy Mini: pictures, faces, and questions to a vision model.

Pictures live in the shared images directory; tools name them by the relative path
``take_picture`` returns. Tools that take a ``path`` take a new picture when it is omitted.
"""

from __future__ import annotations

import asyncio
from typing import Annotated, Any

from fastmcp import FastMCP
from fastmcp.tools.base import ToolResult
from pydantic import Field

from rosaos.devices.images import MAX_IMAGE_BYTES, image_budget, picture_result
from rosaos.drivers import DeviceError
from rosaos_reachy.annotations import ACT, CLOUD_READ, DELETE, READ_ONLY
from rosaos_reachy.backend import ReachyBackend
from rosaos_reachy.camera import jpeg_for_model
from rosaos_reachy.faces import Face, FaceAnalysis, face_from_box
from rosaos_reachy.local_vision import describe_locally
from rosaos_reachy.state import FacesReport, MotionReport, PictureReport
from rosaos_reachy.vision import load_image

ImagePath = Annotated[
    str | None,
    Field(max_length=300, description="A picture path from take_picture; omit to take a new picture."),
]
Question = Annotated[str, Field(min_length=1, max_length=500, description="What to ask about the picture.")]
PersonName = Annotated[str, Field(min_length=1, max_length=40, description="The person's name.")]
NOTE = "OpenCV Haar cascades, offline; 'looks_like' compares with remembered faces and can be wrong."


def register(mcp: FastMCP, backend: ReachyBackend) -> None:
    """Add the camera, face and vision-model tools to ``mcp``."""

    async def picture(path: str | None) -> tuple[str, Any]:
        if path is None:
            report, image = await backend.take_picture()
            return report.path, image
        image, _ = await asyncio.to_thread(load_image, backend.images_dir, path)
        return path, image

    async def faces_in(path: str | None) -> tuple[str, Any, list[tuple[int, int, int, int]]]:
        if backend.detector is None:
            raise DeviceError("the face detector is not loaded; the device is still starting")
        name, image = await picture(path)
        boxes = await asyncio.to_thread(backend.detector.detect, image)
        return name, image, boxes

    @mcp.tool(annotations=ACT)
    async def take_picture() -> PictureReport | ToolResult:
        """Take a picture with the robot's camera; returns its path in the shared images directory.

        In simulation the picture is generated (``simulated`` is true) and says so. If you can
        see images, the picture comes with it.
        """
        max_px = image_budget()
        report, image = await backend.take_picture()
        if max_px is None:  # a text-only model: the path (describe_image says what is in it)
            return report
        jpeg = await asyncio.to_thread(jpeg_for_model, image, max_px, MAX_IMAGE_BYTES)
        return picture_result(report.model_dump(), jpeg)

    @mcp.tool(annotations=CLOUD_READ)
    async def describe_image(path: ImagePath = None, question: Question = "Describe what you see.") -> str:
        """Ask the vision model about a picture ("who is there?", "is the window open?").

        With a configured vision model (Groq's Llama 4 Scout, or an OpenAI-compatible endpoint)
        the picture is sent to that service. Without one, a description made on this computer:
        people and faces found, the main colours and the brightness, which cannot answer
        ``question`` in detail.
        """
        _, image = await picture(path)
        if not backend.vision.configured:
            names = []
            if backend.detector is not None:
                for box in await asyncio.to_thread(backend.detector.detect, image):
                    looks_like, _ = await asyncio.to_thread(backend.face_memory.match, image, box)
                    names.append(looks_like)
            return await asyncio.to_thread(describe_locally, image, names)
        return await backend.vision.describe(image, question)

    @mcp.tool(annotations=READ_ONLY)
    async def detect_faces(path: ImagePath = None) -> FacesReport:
        """Find faces in a picture, largest first, each with its box, its centre in [-1, 1]
        coordinates, and which remembered person it looks like. Works offline."""
        name, image, boxes = await faces_in(path)
        faces = []
        for box in boxes:
            looks_like, similarity = await asyncio.to_thread(backend.face_memory.match, image, box)
            faces.append(Face(**face_from_box(image, box), looks_like=looks_like, similarity=similarity))
        return FacesReport(
            path=name, count=len(faces), faces=faces, remembered=backend.face_memory.names(), note=NOTE
        )

    @mcp.tool(annotations=ACT)
    async def remember_face(name: PersonName, path: ImagePath = None) -> str:
        """Remember the largest face in a picture as ``name``, so detect_faces can recognise it.

        Several pictures of one person make it more reliable. Stored on this computer only.
        """
        picture_name, image, boxes = await faces_in(path)
        if not boxes:
            raise DeviceError(f"no face in {picture_name}; ask the person to face the camera, then try again")
        samples = await asyncio.to_thread(backend.face_memory.remember, name.strip(), image, boxes[0])
        return (
            f"remembered {name.strip()} ({samples} picture{'s' if samples > 1 else ''}) from {picture_name}"
        )

    @mcp.tool(annotations=DELETE)
    async def forget_face(name: PersonName) -> str:
        """Delete everything remembered about ``name``'s face."""
        if await asyncio.to_thread(backend.face_memory.forget, name.strip()):
            return f"forgot {name.strip()}"
        return f"no face remembered as {name.strip()}; remembered: {', '.join(backend.face_memory.names()) or 'none'}"

    @mcp.tool(annotations=READ_ONLY)
    async def analyze_face(path: ImagePath = None) -> FaceAnalysis:
        """Look closer at the largest face: where it is, how close, eyes visible, smiling, the
        light, and who it looks like. Rough offline cues, not emotion recognition."""
        picture_name, image, boxes = await faces_in(path)
        if not boxes or backend.detector is None:
            raise DeviceError(f"no face in {picture_name}; ask the person to face the camera, then try again")
        box = boxes[0]
        eyes, smiling, brightness = await asyncio.to_thread(backend.detector.analyze, image, box)
        looks_like, similarity = await asyncio.to_thread(backend.face_memory.match, image, box)
        return FaceAnalysis(
            **face_from_box(image, box),
            looks_like=looks_like,
            similarity=similarity,
            eyes_visible=eyes,
            smiling=smiling,
            brightness=brightness,
            size=round(box[2] / image.shape[1], 2),
        )

    @mcp.tool(annotations=ACT)
    async def look_at_face() -> MotionReport:
        """Take a picture and turn the head toward the largest face in it (eye contact).

        Says so, and does not move, when nobody is in view.
        """
        name, image, boxes = await faces_in(None)
        if not boxes:
            return backend.report(f"no face in view ({name}); the head did not move")
        x, y, w, h = boxes[0]
        height, width = image.shape[:2]
        return await backend.look_toward_pixel(x + w / 2, y + h / 2, width, height, f"at the face in {name}")
