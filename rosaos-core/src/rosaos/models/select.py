"""Model selection: turn a serializable :class:`ModelSpec` into a pydantic-ai model.

A spec crosses the pipe to worker processes, so it is data, not a model object. Its ``model``:

- ``None``: the offline default (no key, no endpoint needed).
- any pydantic-ai model string: ``openai:gpt-5.2``, ``anthropic:...``, ``google:...``,
  ``groq:...``; keys come from the provider's usual environment variable.
- ``openai-compatible`` with ``base_url`` and ``model_name`` (vLLM, Ollama, llama.cpp).
- ``python:package.module:attribute``: a ``Model`` object, or a zero-argument factory returning
  one. This is how tests give workers a ``FunctionModel``, and how a plugin can ship a model.
"""

from __future__ import annotations

import importlib
from typing import Any

from pydantic import BaseModel, ConfigDict
from pydantic_ai.models import Model, infer_model

OPENAI_COMPATIBLE = "openai-compatible"
PYTHON_PREFIX = "python:"
LEGACY_PREFIXES = {"google-gla:": "google:"}
"""Provider prefixes from older pydantic-ai docs, mapped to the names the pinned version knows."""


class ModelError(Exception):
    """A model spec that cannot be turned into a model; the message says how to fix it."""


class ModelSpec(BaseModel):
    """Which model to run, as data."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    model: str | None = None
    base_url: str | None = None
    api_key: str | None = None
    model_name: str | None = None
    prefer_local: bool = True
    """With a model set: tasks the offline engine planned still run locally (no LLM call)."""
    language: str = "en"
    """Language of the offline engine's replies."""
    vision: bool | None = None
    """Whether the model takes images; ``None``: its pydantic-ai profile says."""
    image_max_px: int = 768
    """Longest side of a picture sent to the model, in pixels."""

    @property
    def is_offline_default(self) -> bool:
        return self.model is None

    def describe(self) -> str:
        """Short human description, without secrets."""
        if self.model is None:
            return "offline default"
        if self.model == OPENAI_COMPATIBLE:
            return f"{self.model_name} at {self.base_url}"
        return self.model


def build_model(spec: ModelSpec, *, offline: Model | None = None) -> Model:
    """Build the pydantic-ai model for ``spec``. ``offline`` is used when ``spec.model`` is None."""
    if spec.model is None:
        if offline is None:
            raise ModelError("no model configured and no offline model given")
        return offline
    if spec.model.startswith(PYTHON_PREFIX):
        return _import_model(spec.model[len(PYTHON_PREFIX) :])
    if spec.model == OPENAI_COMPATIBLE:
        return _openai_compatible(spec)
    name = spec.model
    for old, new in LEGACY_PREFIXES.items():
        if name.startswith(old):
            name = new + name[len(old) :]
    try:
        return infer_model(name)
    except Exception as error:  # pydantic-ai raises UserError / ImportError with useful text
        raise ModelError(f"cannot use model {spec.model!r}: {error}") from None


def _import_model(target: str) -> Model:
    module_name, _, attribute = target.partition(":")
    if not module_name or not attribute:
        raise ModelError(f"python model {target!r} must look like 'package.module:attribute'")
    try:
        value: Any = getattr(importlib.import_module(module_name), attribute)
    except (ImportError, AttributeError) as error:
        raise ModelError(f"cannot import model {target!r}: {error}") from None
    if not isinstance(value, Model) and callable(value):
        value = value()
    if not isinstance(value, Model):
        raise ModelError(f"{target!r} is not a pydantic-ai Model or a factory returning one")
    return value


def _openai_compatible(spec: ModelSpec) -> Model:
    if not spec.base_url or not spec.model_name:
        raise ModelError(
            "model 'openai-compatible' needs base_url and model_name, e.g. "
            "--base-url http://127.0.0.1:11434/v1 --model-name qwen3:8b"
        )
    from pydantic_ai.models.openai import OpenAIChatModel
    from pydantic_ai.providers.openai import OpenAIProvider

    # Local servers (Ollama, llama.cpp) ignore the key, but the client insists on one.
    provider = OpenAIProvider(base_url=spec.base_url, api_key=spec.api_key or "not-needed")
    return OpenAIChatModel(spec.model_name, provider=provider)
