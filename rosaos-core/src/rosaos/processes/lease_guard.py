"""Calls a process agent makes to tools it was not given: logged, and answered by the lease that is missing.

A model that holds the kitchen light may still call ``living_room_lamp_turn_on`` (it read about
the lamp somewhere) or a tool name it made up. pydantic-ai answers such a call with "Unknown tool
name ... Available tools: ..." and nothing records it. :class:`LeaseGuardModel` wraps the process
model and, for every call to a tool that was not offered:

- adds a failed :class:`~rosaos.receipts.Receipt` (the callback's tool list, ``rosaos log``);
- rewrites the answer the model reads next to say what is wrong: "process 7 holds no lease on
  living_room_lamp", with the devices it does hold, instead of a list of every tool name.

The model can still correct itself with a tool it holds; the process is judged on its real calls.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from typing import Any, cast

from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelRequestPart,
    ModelResponse,
    RetryPromptPart,
    ToolCallPart,
    ToolReturnPart,
)
from pydantic_ai.models import Model, ModelRequestParameters
from pydantic_ai.models.wrapper import WrapperModel
from pydantic_ai.settings import ModelSettings

from rosaos.receipts import Receipt, redact

UNLEASED = "(not leased)"
"""The receipt's device for a call whose tool name names no device at all."""


class LeaseGuardModel(WrapperModel):
    """``wrapped``, with calls to tools the process was not given logged and explained."""

    def __init__(
        self,
        wrapped: Model,
        process_id: int,
        granted: Sequence[str],
        world: Sequence[str],
        receipts: list[Receipt],
    ) -> None:
        super().__init__(wrapped)
        self.process_id = process_id
        self.granted = list(granted)
        self.world = sorted(world, key=len, reverse=True)  # longest first: "lamp_2" before "lamp"
        self.receipts = receipts
        self._refusals: dict[str, str] = {}
        """tool call id → what the model is told about that call."""

    async def request(
        self,
        messages: list[ModelMessage],
        model_settings: ModelSettings | None,
        model_request_parameters: ModelRequestParameters,
    ) -> ModelResponse:
        """Explain earlier refused calls, ask the model, and note the calls it makes to tools it lacks."""
        response = await self.wrapped.request(
            self._explained(messages), model_settings, model_request_parameters
        )
        offered = {tool.name for tool in model_request_parameters.function_tools}
        offered |= {tool.name for tool in model_request_parameters.output_tools}
        for part in response.parts:
            if isinstance(part, ToolCallPart) and part.tool_name not in offered:
                device, message = self.refusal(part.tool_name, sorted(offered))
                self._refusals[part.tool_call_id] = message
                self.receipts.append(
                    Receipt(
                        device=device,
                        tool=part.tool_name,
                        arguments=redact(_arguments(part)),
                        ok=False,
                        error=message,
                        started=time.time(),
                        duration=0.0,
                    )
                )
        return response

    def refusal(self, tool: str, offered: Sequence[str]) -> tuple[str, str]:
        """The device a call to ``tool`` was meant for (or :data:`UNLEASED`), and what to tell the model."""
        holds = ", ".join(self.granted) or "no devices"
        device = next(
            (name for name in self.world if tool.startswith(f"{name}_") and name not in self.granted), None
        )
        if device is not None:
            return device, (
                f"process {self.process_id} holds no lease on {device}; it holds {holds}. Do not retry: "
                f"report that the task needs {device}, so the kernel can launch a process with it."
            )
        return UNLEASED, (
            f"process {self.process_id} holds no lease on a device with a tool {tool!r}; it holds {holds}, "
            f"whose tools are: {', '.join(offered) or 'none'}."
        )

    def _explain(self, part: ModelRequestPart) -> ModelRequestPart:
        """pydantic-ai's answer to a refused call (a retry prompt, or a tool return marked retried,
        depending on its version) with the lease's words; any other part as it is."""
        if isinstance(part, RetryPromptPart) and part.tool_call_id in self._refusals:
            return dataclasses.replace(part, content=self._refusals[part.tool_call_id])
        if (
            isinstance(part, ToolReturnPart)
            and part.outcome != "success"
            and part.tool_call_id in self._refusals
        ):
            returned = cast("ToolReturnPart[Any]", part)
            return dataclasses.replace(returned, content=self._refusals[part.tool_call_id])
        return part

    def _explained(self, messages: list[ModelMessage]) -> list[ModelMessage]:
        """``messages`` with pydantic-ai's "Unknown tool name" answers replaced by the lease's word."""
        if not self._refusals:
            return messages
        explained: list[ModelMessage] = []
        for message in messages:
            if isinstance(message, ModelRequest):
                parts = [self._explain(part) for part in message.parts]
                if any(new is not old for new, old in zip(parts, message.parts, strict=True)):
                    message = dataclasses.replace(message, parts=parts)
            explained.append(message)
        return explained


def _arguments(call: ToolCallPart) -> dict[str, object]:
    try:
        return call.args_as_dict()
    except Exception:  # arguments that are not a JSON object: keep them as text
        return {"arguments": str(call.args)[:500]}
