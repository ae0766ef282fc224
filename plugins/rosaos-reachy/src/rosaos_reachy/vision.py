"""``describe_image``: ask a vision-language model about a picture, over the OpenAI chat API.

Groq's Llama 4 Scout by default (``GROQ_API_KEY``), or any OpenAI-compatible endpoint that
takes image input (``vision_base_url``: OpenAI, a vLLM or Ollama server, ...). The picture is
sent inline as a base64 data URL, so the endpoint needs no access to this machine.
"""

from __future__ import annotations

import base64
from pathlib import Path
from typing import Any

import cv2
import httpx
import numpy as np

from rosaos.drivers import DeviceError
from rosaos_reachy.settings import GROQ_BASE_URL, ReachySettings, env_secret

MAX_SIDE = 1024
"""Pictures are scaled down to this many pixels on their longer side before sending."""
NO_VISION_MODEL = (
    "no vision model configured: set GROQ_API_KEY (Groq's Llama 4 Scout is the default), or "
    "[devices.<reachy>] vision_base_url (+ vision_api_key, vision_model) for any OpenAI-compatible "
    "vision endpoint. detect_faces and analyze_face work offline without one."
)


class VisionModel:
    """One configured vision endpoint."""

    def __init__(self, settings: ReachySettings) -> None:
        self.base_url = (settings.vision_base_url or GROQ_BASE_URL).rstrip("/")
        is_groq = settings.vision_base_url is None or self.base_url.startswith(GROQ_BASE_URL)
        names = ("GROQ_API_KEY",) if is_groq else ("OPENAI_API_KEY",)
        self.key = env_secret(settings.vision_api_key, *names)
        self.model = settings.vision_model
        self.timeout = settings.vision_timeout
        # Groq needs a key; a self-hosted endpoint the user named explicitly may not.
        self.configured = bool(self.key) or settings.vision_base_url is not None

    async def describe(self, image: np.ndarray[Any, Any], question: str) -> str:
        """The model's answer to ``question`` about ``image``; :class:`DeviceError` says what failed."""
        if not self.configured:
            raise DeviceError(NO_VISION_MODEL)
        body = {
            "model": self.model,
            "max_tokens": 400,
            "messages": [
                {
                    "role": "user",
                    "content": [
                        {"type": "text", "text": question},
                        {"type": "image_url", "image_url": {"url": data_url(image)}},
                    ],
                }
            ],
        }
        headers = {"Authorization": f"Bearer {self.key}"} if self.key else {}
        try:
            async with httpx.AsyncClient(timeout=self.timeout) as http:
                response = await http.post(f"{self.base_url}/chat/completions", json=body, headers=headers)
        except httpx.HTTPError as error:
            raise DeviceError(
                f"the vision model at {self.base_url} is unreachable ({type(error).__name__}: {error}); "
                "check vision_base_url and the network"
            ) from None
        if response.status_code >= 400:
            raise DeviceError(
                f"the vision model answered HTTP {response.status_code}: {response.text[:300].strip()}; "
                "check vision_api_key and vision_model"
            )
        try:
            content = response.json()["choices"][0]["message"]["content"]
        except (ValueError, KeyError, IndexError, TypeError):
            raise DeviceError(
                f"the vision model's answer is not an OpenAI chat completion: {response.text[:200]}"
            ) from None
        if isinstance(content, list):  # some servers return content parts
            content = " ".join(part.get("text", "") for part in content if isinstance(part, dict))
        return str(content).strip()


def data_url(image: np.ndarray[Any, Any]) -> str:
    """``image`` as a ``data:image/jpeg;base64,...`` URL, at most :data:`MAX_SIDE` pixels a side."""
    scale = MAX_SIDE / max(image.shape[:2])
    if scale < 1.0:
        image = cv2.resize(image, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    ok, jpeg = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 85])
    if not ok:
        raise DeviceError("could not encode the picture as JPEG")
    return "data:image/jpeg;base64," + base64.b64encode(jpeg.tobytes()).decode("ascii")


def load_image(images_dir: Path, path: str) -> tuple[np.ndarray[Any, Any], Path]:
    """Read a picture named relative to the images directory (as ``take_picture`` returns it)."""
    root = images_dir.resolve()
    candidate = (root / path).resolve()
    if not candidate.is_relative_to(root):
        raise DeviceError(f"{path!r} is outside the images directory; pass a path take_picture returned")
    if not candidate.is_file():
        raise DeviceError(f"no picture {path!r} in the images directory; call take_picture first")
    image = cv2.imread(str(candidate))
    if image is None:
        raise DeviceError(f"{path!r} is not a picture OpenCV can read (JPEG or PNG)")
    return image, candidate
