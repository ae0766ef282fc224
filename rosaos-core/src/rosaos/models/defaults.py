"""Which models a kernel runs, from the configuration: the LLM if one is set, else the offline default."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from pydantic_ai.models import Model

from rosaos.config import RosaosConfig
from rosaos.models.select import ModelSpec, build_model

if TYPE_CHECKING:
    from rosaos.devices.world import World
    from rosaos.events.types import Event
    from rosaos.models.kernel_model import LocalIntentModel


@dataclass
class KernelModels:
    """The kernel's model, the spec its processes run on, and how to describe them to people."""

    kernel: Model
    process: ModelSpec
    description: str
    notice: str | None
    for_event: Callable[[Event], Model | None]
    """Per-event override of the kernel model (the offline fast path), None for the default."""
    local: LocalIntentModel | None = None
    """The offline engine, also when an LLM is the kernel (None only for a test's override model).
    The kernel gives it memory (aliases, places), and the voice front end asks it whether a draft
    transcript is a whole command (``POST /understand``)."""


OFFLINE_NOTICE = (
    'Running offline: the local-intent engine understands direct commands ("turn on the kitchen '
    'light", "play some jazz"). For open-ended requests set a model: `rosaos up --model '
    "openai:gpt-5.2` (or anthropic:…, google:…, groq:…), or `--model openai-compatible "
    "--base-url http://127.0.0.1:11434/v1 --model-name qwen3:8b`."
)


def kernel_spec(config: RosaosConfig) -> ModelSpec:
    """The kernel's model as configured."""
    models = config.models
    return ModelSpec(
        model=models.kernel,
        base_url=models.base_url,
        api_key=models.api_key,
        model_name=models.model_name,
        prefer_local=models.prefer_local,
        language=models.language,
        vision=models.vision,
        image_max_px=models.image_max_px,
    )


def process_spec(config: RosaosConfig) -> ModelSpec:
    """The process agents' model: ``[models] process``, else the kernel's."""
    models = config.models
    return kernel_spec(config).model_copy(update={"model": models.process or models.kernel})


def kernel_models(config: RosaosConfig, world: World, override: Model | None = None) -> KernelModels:
    """Resolve the configured models. ``override`` (tests) replaces the kernel model outright.

    No model configured: the offline local-intent engine is the kernel. A model configured: it
    is the kernel, and with ``prefer_local`` the engine still takes the sentences it matches.
    """
    from rosaos.intents.grammar.vocabulary import device_vocabularies
    from rosaos.models.kernel_model import LocalIntentModel
    from rosaos.models.routing import KernelRouter

    spec = kernel_spec(config)
    process = process_spec(config)
    if override is not None:
        return KernelModels(override, process, override.model_name, None, lambda event: None)
    speaker = next((i.name for i in world.instances.values() if i.spec.always_attached), None)
    local = LocalIntentModel(device_vocabularies(world), language=config.models.language, speaker=speaker)
    if spec.model is None:
        return KernelModels(
            local, process, "offline local-intent engine", OFFLINE_NOTICE, lambda event: None, local
        )
    llm = build_model(spec)
    router = KernelRouter(local, llm, prefer_local=spec.prefer_local)
    description = spec.describe() + (" (exact commands run offline)" if spec.prefer_local else "")
    return KernelModels(llm, process, description, None, router.model_for_event, local)
