"""Choosing between the offline engine and an LLM (``[models] prefer_local``).

With no LLM configured the local models do everything. With one configured:

- ``prefer_local = true`` (default): sentences the local-intent engine matches exactly skip the
  LLM (fast, free, deterministic); everything else goes to the LLM. Callbacks of processes the
  engine planned, and processes whose job carries a plan, stay local too.
- ``prefer_local = false``: everything goes to the LLM.

Two ways to plug this in, pick whichever fits the call site:

- functions: :meth:`KernelRouter.model_for_event` is a ``KernelLoop(model=...)`` callback (a
  model per event, None = the agent's own model), and :func:`process_model_for` picks a worker's
  model from its job's plan;
- :class:`RoutingModel`: one ``Model`` object that decides per request, for places that take a
  single model (e.g. a ``python:`` model spec).
"""

from __future__ import annotations

from collections.abc import AsyncIterator, Sequence
from contextlib import asynccontextmanager
from typing import Any, Protocol

from pydantic_ai import RunContext
from pydantic_ai.messages import ModelMessage, ModelResponse
from pydantic_ai.models import Model, ModelRequestParameters, StreamedResponse
from pydantic_ai.models.wrapper import WrapperModel
from pydantic_ai.settings import ModelSettings

from rosaos.events.plan import Plan
from rosaos.events.types import Event
from rosaos.models.kernel_model import LocalIntentModel
from rosaos.models.process_model import LocalPlanModel


class LocalModel(Protocol):
    """What :class:`RoutingModel` needs of a local model: can it answer this request?"""

    def handles(self, messages: Sequence[ModelMessage]) -> bool: ...


class KernelRouter:
    """Picks the kernel's model per event: the local engine or the LLM."""

    def __init__(self, local: LocalIntentModel, llm: Model | None, prefer_local: bool = True) -> None:
        self.local = local
        self.llm = llm
        self.prefer_local = prefer_local

    def model_for_event(self, event: Event) -> Model:
        """``KernelLoop(model=router.model_for_event)``: the model for one kernel event, chosen
        from the typed event (nothing is rendered to choose)."""
        if self.llm is None:
            return self.local
        if self.prefer_local and self.local.handles_event(event):
            return self.local
        return self.llm


def process_model_for(
    plan: Plan | None, llm: Model | None, prefer_local: bool = True, language: str = "en"
) -> Model:
    """A worker's model for a job with ``plan``: the plan runner when there is a plan (and local
    is preferred, or there is no LLM), else the LLM."""
    if llm is None or (prefer_local and plan is not None):
        return LocalPlanModel(language, plan)
    return llm


class RoutingModel(WrapperModel):
    """One model that sends each request to ``local`` when it handles it, else to ``llm``.

    ``local`` is a :class:`LocalIntentModel` (kernel) or :class:`LocalPlanModel` (process). A run
    that began on one model stays on it: the local models check who answered earlier in the turn.
    """

    def __init__(
        self, local: LocalIntentModel | LocalPlanModel, llm: Model, prefer_local: bool = True
    ) -> None:
        super().__init__(llm)
        self.local = local
        self.prefer_local = prefer_local

    @property
    def model_name(self) -> str:
        """Both names, so logs show the routing."""
        return f"{self.local.model_name}|{self.wrapped.model_name}"

    def _pick(self, messages: Sequence[ModelMessage]) -> Model:
        if self.prefer_local and self.local.handles(messages):
            return self.local
        return self.wrapped

    async def request(
        self,
        messages: list[ModelMessage],
        model_settings: ModelSettings | None,
        model_request_parameters: ModelRequestParameters,
    ) -> ModelResponse:
        """Answer with whichever model :meth:`_pick` chooses."""
        return await self._pick(messages).request(messages, model_settings, model_request_parameters)

    @asynccontextmanager
    async def request_stream(
        self,
        messages: list[ModelMessage],
        model_settings: ModelSettings | None,
        model_request_parameters: ModelRequestParameters,
        run_context: RunContext[Any] | None = None,
    ) -> AsyncIterator[StreamedResponse]:
        """Streaming goes to the LLM (the local models answer at once and do not stream)."""
        async with self.wrapped.request_stream(
            messages, model_settings, model_request_parameters, run_context
        ) as response:
            yield response
