"""Which models a kernel runs, from the configuration: the LLM if one is set, else the offline default."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from pydantic_ai.messages import ModelMessage, ModelResponse, TextPart
from pydantic_ai.models import Model
from pydantic_ai.models.function import AgentInfo, FunctionModel

from rosaos.config import RosaosConfig
from rosaos.models.select import ModelSpec, build_model

if TYPE_CHECKING:
    from rosaos.devices.world import World
    from rosaos.kernel.events import Event

NO_MODEL_NOTICE = (
    "No model is configured. Set one with `rosaos up --model openai:gpt-5.2` (or anthropic:…, "
    "google-gla:…, groq:…, with the provider's API key in its usual environment variable), or "
    "`--model openai-compatible --base-url http://127.0.0.1:11434/v1 --model-name qwen3:8b` for a "
    "local server, or [models] kernel in rosaos.toml."
)


@dataclass
class KernelModels:
    """The kernel's model, the spec its processes run on, and how to describe them to people."""

    kernel: Model
    process: ModelSpec
    description: str
    notice: str | None
    for_event: Callable[[Event], Model | None]
    """Per-event override of the kernel model (the offline fast path), None for the default."""


def kernel_spec(config: RosaosConfig) -> ModelSpec:
    models = config.models
    return ModelSpec(
        model=models.kernel, base_url=models.base_url, api_key=models.api_key, model_name=models.model_name
    )


def process_spec(config: RosaosConfig) -> ModelSpec:
    models = config.models
    return ModelSpec(
        model=models.process or models.kernel,
        base_url=models.base_url,
        api_key=models.api_key,
        model_name=models.model_name,
    )


def kernel_models(config: RosaosConfig, world: World, override: Model | None = None) -> KernelModels:
    """Resolve the configured models. ``override`` (tests) replaces the kernel model outright."""
    spec = kernel_spec(config)
    process = process_spec(config)
    if override is not None:
        return KernelModels(override, process, override.model_name, None, lambda event: None)
    if spec.model is None:
        model = unconfigured_model()
        return KernelModels(model, process, "none", NO_MODEL_NOTICE, lambda event: None)
    return KernelModels(build_model(spec), process, spec.describe(), None, lambda event: None)


def unconfigured_model() -> Model:
    """Answers every event by saying how to configure a model, so the system still runs end to end."""

    def answer(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        return ModelResponse(parts=[TextPart(NO_MODEL_NOTICE)])

    return FunctionModel(answer, model_name="rosaos-unconfigured")
