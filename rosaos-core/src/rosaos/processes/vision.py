"""Whether a process's model takes images, and what happens when a provider refuses one.

As in the rosaOS paper, vision stays out of the core model by default: a camera tool returns the
picture's path, and a describe tool (the Reachy's ``describe_image``) answers questions about it,
with the configured vision model when there is one, else locally. Image parts go only to a model
declared multimodal: ``[models] vision = true``, or, with ``vision`` unset, a model named by a
cloud provider's pydantic-ai string whose profile says it takes images (``supports_image_input``).
An ``openai-compatible`` endpoint or a ``python:`` model gets pictures only when declared; a
local server behind it is often text-only. The answer travels to each device as the
:data:`~rosaos.devices.images.IMAGES_HEADER` of its MCP session.

When a provider answers 400 to a request with an image in it anyway, :class:`ImageFallbackModel`
sends it again once without the image, with a note saying why, and keeps images out from then on.
"""

from __future__ import annotations

import dataclasses
import logging
from typing import Any

from pydantic_ai.exceptions import ModelHTTPError, ModelRequestRejectedError
from pydantic_ai.messages import BinaryContent, ImageUrl, ModelMessage, ModelRequest, ModelResponse
from pydantic_ai.models import Model, ModelRequestParameters
from pydantic_ai.models.wrapper import WrapperModel
from pydantic_ai.settings import ModelSettings

from rosaos.devices.images import IMAGES_HEADER
from rosaos.models.process_model import LocalPlanModel
from rosaos.models.select import OPENAI_COMPATIBLE, PYTHON_PREFIX, ModelSpec

log = logging.getLogger(__name__)

IMAGE_REMOVED = (
    "[a picture was here; this model refused image input, so it was removed. Its path is in the "
    "tool's result: ask describe_image about it if you need to know what it shows]"
)


def image_budget_for(spec: ModelSpec, model: Model) -> int | None:
    """The longest picture side (px) to send this model, or ``None`` when it takes no images."""
    if spec.vision is False or spec.model is None or isinstance(model, LocalPlanModel):
        return None
    if spec.vision is None:
        declared_only = spec.model == OPENAI_COMPATIBLE or spec.model.startswith(PYTHON_PREFIX)
        if declared_only or not model.profile.get("supports_image_input", False):
            return None
    return spec.image_max_px


def image_headers(budget: int | None) -> dict[str, str]:
    """The HTTP headers that tell a device's camera tools what the model takes."""
    return {} if budget is None else {IMAGES_HEADER: str(budget)}


class ImageFallbackModel(WrapperModel):
    """``wrapped``, retried once without its images when the provider rejects a request that has some."""

    def __init__(self, wrapped: Model) -> None:
        super().__init__(wrapped)
        self.refused_images = False
        """Set once the provider refused a picture: later requests go without pictures."""

    async def request(
        self,
        messages: list[ModelMessage],
        model_settings: ModelSettings | None,
        model_request_parameters: ModelRequestParameters,
    ) -> ModelResponse:
        """The wrapped model's answer; on a 400 to a request with images, the answer without them."""
        if self.refused_images:
            messages = without_images(messages)
        try:
            return await self.wrapped.request(messages, model_settings, model_request_parameters)
        except (ModelRequestRejectedError, ModelHTTPError) as rejected:
            status = getattr(rejected, "status_code", 400)
            if self.refused_images or status != 400 or not has_images(messages):
                raise
            log.warning("the model refused a request with a picture (%s); sending it again without", rejected)
            self.refused_images = True
            return await self.wrapped.request(
                without_images(messages), model_settings, model_request_parameters
            )


def _is_image(item: Any) -> bool:
    return isinstance(item, ImageUrl) or (isinstance(item, BinaryContent) and item.is_image)


def has_images(messages: list[ModelMessage]) -> bool:
    """Whether any request part of ``messages`` carries a picture."""
    return any(
        isinstance(message, ModelRequest)
        and any(
            isinstance(content := getattr(part, "content", None), list) and any(map(_is_image, content))
            for part in message.parts
        )
        for message in messages
    )


def without_images(messages: list[ModelMessage]) -> list[ModelMessage]:
    """``messages`` with every picture replaced by :data:`IMAGE_REMOVED`."""
    cleaned: list[ModelMessage] = []
    for message in messages:
        if isinstance(message, ModelRequest):
            parts = []
            for part in message.parts:
                content = getattr(part, "content", None)
                if isinstance(content, list) and any(map(_is_image, content)):
                    kept = [IMAGE_REMOVED if _is_image(item) else item for item in content]
                    part = dataclasses.replace(part, content=kept)  # type: ignore[arg-type]
                parts.append(part)
            message = dataclasses.replace(message, parts=parts)
        cleaned.append(message)
    return cleaned
