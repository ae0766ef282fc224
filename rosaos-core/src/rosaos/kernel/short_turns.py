"""Kernel steps that need no model request, so a one-device command costs the LLM three requests.

The paper's loop stays: every event, callbacks included, enters the kernel's history, and the
model decides everything that needs deciding. Two steps need no decision:

- **The acknowledgement after a launch.** When the model's last step only called
  ``launch_process`` and every launch was accepted, the turn ends with the words the model wrote
  next to its calls (the prompt asks for them there), or "On it." A refused launch goes back to
  the model, which decides what to do about the holder (:class:`LaunchAckModel`).
- **Relaying a report.** A process that ended ``ok``, with a report and no follow-up waiting on it,
  is relayed to the user in its own words (the process prompt says the report is what the user
  hears). Failures, ``unverified`` ends and follow-ups go to the model (:func:`relayable`).
"""

from __future__ import annotations

from pydantic_ai.messages import ModelMessage, ModelRequest, ModelResponse, TextPart, UserPromptPart
from pydantic_ai.models import ModelRequestParameters
from pydantic_ai.models.wrapper import WrapperModel
from pydantic_ai.settings import ModelSettings

from rosaos.events.callback import WorkerCallback
from rosaos.events.types import Event
from rosaos.models.conversation import report_with_accepted_calls

LAUNCH_TOOL = "launch_process"
ACK_MODEL = "rosaos-launch-ack"
"""The ``model_name`` of an acknowledgement the kernel wrote without asking the model."""
RELAY_MODEL = "rosaos-relay"
"""The ``model_name`` of a relayed report in the kernel's history."""
DEFAULT_ACK = "On it."
NO_OUTPUT = "(no output)"


def launch_ack(messages: list[ModelMessage]) -> str | None:
    """The words that end a turn whose last step only launched processes, all accepted; else None."""
    finished = report_with_accepted_calls(messages)
    if finished is None or any(call.tool_name != LAUNCH_TOOL for call in finished[0]):
        return None
    return finished[1] or DEFAULT_ACK


class LaunchAckModel(WrapperModel):
    """The kernel's model, except that an accepted launch ends the turn without another request."""

    async def request(
        self,
        messages: list[ModelMessage],
        model_settings: ModelSettings | None,
        model_request_parameters: ModelRequestParameters,
    ) -> ModelResponse:
        """:func:`launch_ack` when it applies, else the wrapped model's answer."""
        ack = launch_ack(messages)
        if ack is not None:
            return ModelResponse(parts=[TextPart(ack)], model_name=ACK_MODEL)
        return await self.wrapped.request(messages, model_settings, model_request_parameters)


def relayable(event: Event) -> str | None:
    """The report to relay for a callback the model has nothing to decide about; None otherwise."""
    if event.kind != "worker_callback":
        return None
    payload = event.payload
    if not isinstance(payload, WorkerCallback) or payload.status != "ok" or has_follow_up(payload):
        return None
    output = (payload.output or "").strip()
    return output if output and output != NO_OUTPUT else None


def has_follow_up(callback: WorkerCallback) -> bool:
    """Whether the kernel launches something on this callback: an LLM's ``then``, or the plan's."""
    return bool(callback.then) or (callback.plan is not None and callback.plan.then is not None)


def relayed_messages(prompt: str, report: str) -> list[ModelMessage]:
    """The history a relayed callback leaves: the event as the model would have read it, and the report."""
    return [
        ModelRequest(parts=[UserPromptPart(prompt)]),
        ModelResponse(parts=[TextPart(report)], model_name=RELAY_MODEL),
    ]
