"""Whether a process's model takes images: decides what the camera tools of its devices send.

``[models] vision`` wins when set; otherwise pydantic-ai's model profile says
(``supports_image_input``). The offline engine reads no pictures. The answer travels to each
device as the :data:`~rosaos.devices.images.IMAGES_HEADER` of its MCP session.
"""

from __future__ import annotations

from pydantic_ai.models import Model

from rosaos.devices.images import IMAGES_HEADER
from rosaos.models.process_model import LocalPlanModel
from rosaos.models.select import ModelSpec


def image_budget_for(spec: ModelSpec, model: Model) -> int | None:
    """The longest picture side (px) to send this model, or ``None`` when it takes no images."""
    if spec.vision is False or spec.model is None or isinstance(model, LocalPlanModel):
        return None
    if spec.vision is None and not model.profile.get("supports_image_input", True):
        return None
    return spec.image_max_px


def image_headers(budget: int | None) -> dict[str, str]:
    """The HTTP headers that tell a device's camera tools what the model takes."""
    return {} if budget is None else {IMAGES_HEADER: str(budget)}
