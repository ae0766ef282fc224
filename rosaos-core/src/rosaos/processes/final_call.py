"""A process agent that writes its report beside its last tool calls ends when they succeed.

The process prompt asks the model to write its one-sentence report in the same response as the
calls that finish the task. When every one of those calls succeeds, :class:`FinalCallModel`
answers the next request itself with that report, so a light switch costs the process one model
request instead of two. If any call failed (or named a tool the process lacks), the model is asked
as usual and can read the error. Whatever the model wrote, the process is judged on its receipts
(processes/tool_calls.py): a report written before the result is only kept if the call succeeded.
"""

from __future__ import annotations

from pydantic_ai.messages import ModelMessage, ModelResponse, TextPart
from pydantic_ai.models import ModelRequestParameters
from pydantic_ai.models.wrapper import WrapperModel
from pydantic_ai.settings import ModelSettings

from rosaos.models.conversation import report_with_accepted_calls

FINAL_CALL_MODEL = "rosaos-final-call"
"""The ``model_name`` of a report the worker took from beside the last calls."""


class FinalCallModel(WrapperModel):
    """The process model, except that a report written beside calls that all succeeded ends the run."""

    async def request(
        self,
        messages: list[ModelMessage],
        model_settings: ModelSettings | None,
        model_request_parameters: ModelRequestParameters,
    ) -> ModelResponse:
        """The report beside the last calls when they all succeeded, else the wrapped model's answer."""
        finished = report_with_accepted_calls(messages)
        if finished is not None and finished[1]:
            return ModelResponse(parts=[TextPart(finished[1])], model_name=FINAL_CALL_MODEL)
        return await self.wrapped.request(messages, model_settings, model_request_parameters)
