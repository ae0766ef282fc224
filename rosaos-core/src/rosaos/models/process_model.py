"""The process agent's offline model: runs the plan of its job, step by step.

The worker gives it the job's typed :class:`~rosaos.events.plan.Plan` (written by the
kernel's local-intent engine, carried on the job). Per request this model looks at what has been
done so far and:

1. calls the next plan step's tool, resolved against the tools the agent really has
   (``turn_on``, ``kitchen_light_turn_on`` or ``kitchen_light__turn_on``: device + tool, either way);
2. after the last step, or at the first failed one, works out the reply: the plan's reply with
   ``{result}`` filled in, the yes/no answer read from the state, or the failure with the error;
3. ends with the reply as its text output, which becomes the process's callback output.

It does not speak the reply itself: the kernel's reply goes to the updates stream, and the voice
front end speaks replies to what it heard through the Reachy Mini. A process that spoke every
confirmation would move the robot's ``last_spoken`` on typed commands and in the task benchmark,
where only an explicit "say …" may change it.

A task without a plan gets an answer saying how to configure an LLM for free-form tasks.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from pydantic_ai.messages import ModelMessage, ModelResponse, ModelResponsePart, TextPart, ToolCallPart
from pydantic_ai.models import Model, ModelRequestParameters
from pydantic_ai.settings import ModelSettings
from pydantic_ai.tools import ToolDefinition

from rosaos.events.plan import Plan, fill_state, render_result, result_data
from rosaos.intents.grammar.phrases import phrase
from rosaos.intents.planning.follow_ups import unmet_output
from rosaos.models.conversation import (
    ToolOutcome,
    content_text,
    current_turn,
    responses_by,
    tool_outcomes,
)

# The worker heads each granted device's prompt section "## <instance> (<driver>)".
NO_PLAN_REPLY = (
    "The offline engine only runs planned tasks, as the kernel's local-intent engine plans "
    "them. This task has none. For free-form tasks configure an LLM: "
    "set [models] process in rosaos.toml (for example 'openai:gpt-5.2', or 'openai-compatible' "
    "with base_url and model_name)."
)


def resolve_tool(device: str, tool: str, tools: Sequence[str]) -> str | None:
    """The agent's name for ``tool`` of ``device``: prefixed (``<device>_<tool>``, ``<device>__<tool>``)
    when the process holds several devices, bare when it holds one."""
    for candidate in (f"{device}_{tool}", f"{device}__{tool}", f"{device}.{tool}", tool):
        if candidate in tools:
            return candidate
    return None


class LocalPlanModel(Model):
    """The offline process model: executes the job's :class:`Plan`; no LLM involved.

    ``plan`` is the job's typed plan (None: a task without one, which this model declines).
    ``language`` is only used for the few messages the engine writes itself; the replies of a
    plan were written by the kernel, in its language.
    """

    def __init__(self, language: str = "en", plan: Plan | None = None) -> None:
        super().__init__()
        self.language = language
        self.plan = plan

    @property
    def model_name(self) -> str:
        """The name responses carry; routing uses it to keep a run on this model."""
        return "rosaos-local-plan"

    @property
    def system(self) -> str:
        """The provider, for telemetry: rosaOS itself."""
        return "rosaos"

    def handles(self, messages: Sequence[ModelMessage]) -> bool:
        """Whether this model should answer: the job has a plan, and no other model began."""
        turn = current_turn(messages)
        if len(turn) > 1 and not responses_by(turn, self.model_name):
            return False
        return self.plan is not None

    async def request(
        self,
        messages: list[ModelMessage],
        model_settings: ModelSettings | None,
        model_request_parameters: ModelRequestParameters,
    ) -> ModelResponse:
        """The next step of the plan, or the final reply (see the module docstring)."""
        model_settings, model_request_parameters = self.prepare_request(
            model_settings, model_request_parameters
        )
        parts = self.respond(messages, model_request_parameters.function_tools)
        return ModelResponse(parts=parts, model_name=self.model_name)

    def respond(
        self, messages: Sequence[ModelMessage], tools: Sequence[ToolDefinition]
    ) -> list[ModelResponsePart]:
        """The response parts for ``messages`` with ``tools`` available."""
        plan = self.plan
        if plan is None:
            return [TextPart(NO_PLAN_REPLY)]
        definitions = {tool.name: tool for tool in tools}
        names = list(definitions)
        outcomes = tool_outcomes(messages)
        done, failed = _progress(plan, outcomes)
        if failed is None and done < len(plan.steps):
            step = plan.steps[done]
            name = resolve_tool(step.device, step.tool, names)
            if name is not None:
                return [ToolCallPart(name, clamp_arguments(step.args, definitions[name]))]
            reason = phrase(
                self.language, "no_tool", tool=step.tool, device=step.device, tools=", ".join(names)
            )
            reply = plan.failure.replace("{error}", reason)
        elif failed is not None:
            reply = plan.failure.replace("{error}", content_text(failed.content))
        else:
            results = [outcome.content for outcome in outcomes[: len(plan.steps)]]
            reply = plan_reply(plan, results)
        return [TextPart(reply)]


def _progress(plan: Plan, outcomes: list[ToolOutcome]) -> tuple[int, ToolOutcome | None]:
    """How many plan steps have run, and the first that failed (later calls are the speech)."""
    for index, outcome in enumerate(outcomes[: len(plan.steps)]):
        if not outcome.ok:
            return index, outcome
    return min(len(outcomes), len(plan.steps)), None


DEVICE_WORDS_MAX = 120
"""Longest ``message`` of a tool result that a reply repeats (a search's hit list is not one)."""


def plan_reply(plan: Plan, results: Sequence[Any]) -> str:
    """The reply after every step of ``plan`` returned ``results``.

    A command's plain "Done: next song." says what was asked, not what happened. Where a device
    says what it did in its result's ``message`` ("Playing Take Five by ….", "Volume 40% → 55%."),
    the reply adds those words: a relative change or a skip is answered with its outcome.
    """
    reply = unmet_output(plan, results) or final_reply(plan, results[-1])
    if reply != plan.reply:  # an answer, a filled state, a follow-up not met: already the outcome
        return reply
    said = [words for result in results if (words := _device_words(result)) is not None]
    return " ".join([reply, *dict.fromkeys(said)])


def _device_words(result: Any) -> str | None:
    value = result_data(result)
    words = value.get("message") if isinstance(value, dict) else None
    if not isinstance(words, str) or not words.strip() or len(words) > DEVICE_WORDS_MAX:
        return None
    words = words.strip()
    words = words[0].upper() + words[1:]  # "awake" -> "Awake.": a sentence of its own
    return words if words[-1] in ".!?" else f"{words}."


def final_reply(plan: Plan, result: Any) -> str:
    """The plan's reply after its last step returned ``result``."""
    value = result_data(result)
    if plan.answer is None:
        reply = plan.reply
    elif not isinstance(value, dict):
        return plan.failure.replace("{error}", f"the device state could not be read: {render_result(value)}")
    else:
        matches = all(value.get(key) == expected for key, expected in plan.answer.when.items())
        reply = plan.answer.yes if matches else plan.answer.no
    if not plan.fills_state:
        return reply.replace("{result}", render_result(value))
    # A key this device's state lacks (a robot without a battery) reads the whole state instead.
    filled = fill_state(reply, value)
    return filled if filled is not None else f"{plan.steps[-1].device}: {render_result(value)}"


def clamp_arguments(args: dict[str, Any], tool: ToolDefinition) -> dict[str, Any]:
    """``args`` with numbers brought within the tool's schema bounds ("30000 K" → the maximum)."""
    properties = tool.parameters_json_schema.get("properties") or {}
    clamped = dict(args)
    for name, value in args.items():
        if isinstance(value, bool) or not isinstance(value, int | float):
            continue
        schema = properties.get(name) or {}
        bounds = [schema, *schema.get("anyOf", [])]
        low = next((b["minimum"] for b in bounds if "minimum" in b), None)
        high = next((b["maximum"] for b in bounds if "maximum" in b), None)
        if low is not None and value < low:
            clamped[name] = low
        elif high is not None and value > high:
            clamped[name] = high
    return clamped
