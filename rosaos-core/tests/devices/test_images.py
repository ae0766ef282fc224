"""Pictures for multimodal models: size bounds, the result shape, and the worker's decision."""

from __future__ import annotations

import base64

from mcp.types import ImageContent, TextContent
from pydantic_ai.models.function import FunctionModel
from pydantic_ai.profiles import ModelProfile

from rosaos.devices.images import IMAGES_HEADER, picture_result, scaled_size
from rosaos.models.process_model import LocalPlanModel
from rosaos.models.select import ModelSpec
from rosaos.processes.vision import image_budget_for, image_headers


def _model(takes_images: bool) -> FunctionModel:
    return FunctionModel(lambda m, i: None, profile=ModelProfile(supports_image_input=takes_images))  # type: ignore[arg-type, return-value]


def test_scaled_size_bounds_the_longer_side_and_never_upscales() -> None:
    assert scaled_size(1280, 720, 640) == (640, 360)
    assert scaled_size(480, 960, 240) == (120, 240)
    assert scaled_size(160, 120, 768) == (160, 120)


def test_a_picture_result_carries_the_report_and_the_jpeg() -> None:
    result = picture_result({"image": "a.jpg"}, b"\xff\xd8jpeg")
    text, image = result.content
    assert isinstance(text, TextContent) and '"image_sent": true' in text.text
    assert isinstance(image, ImageContent) and image.mime_type == "image/jpeg"
    assert base64.b64decode(image.data) == b"\xff\xd8jpeg"
    assert result.structured_content == {"image": "a.jpg", "image_sent": True}


def test_the_profile_decides_unless_config_says() -> None:
    spec = ModelSpec(model="openai:gpt-5.2", image_max_px=512)
    assert image_budget_for(spec, _model(True)) == 512
    assert image_budget_for(spec, _model(False)) is None
    assert image_budget_for(spec.model_copy(update={"vision": False}), _model(True)) is None
    assert image_budget_for(spec.model_copy(update={"vision": True}), _model(False)) == 512


def test_a_local_endpoint_or_a_python_model_gets_pictures_only_when_declared() -> None:
    for name in ("openai-compatible", "python:tests:model"):
        spec = ModelSpec(model=name, base_url="http://127.0.0.1:1/v1", model_name="m")
        assert image_budget_for(spec, _model(True)) is None
        assert image_budget_for(spec.model_copy(update={"vision": True}), _model(False)) == 768


def test_the_offline_engine_gets_no_pictures() -> None:
    assert image_budget_for(ModelSpec(), _model(True)) is None
    assert image_budget_for(ModelSpec(model="openai:gpt-5.2"), LocalPlanModel("en")) is None


def test_the_header_names_the_budget() -> None:
    assert image_headers(None) == {} and image_headers(320) == {IMAGES_HEADER: "320"}
