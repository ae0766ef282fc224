"""The kernel agent's offline model: the local-intent engine as a pydantic-ai ``Model``.

Plugged in where an LLM would be, so the kernel runs unchanged: same queue, same
``launch_process``, same workers, leases and MCP tools. Per request it reads the typed event being
handled (:func:`rosaos.models.conversation.turn_event`, never the text an LLM reads) and answers:

- what the user said or typed (:class:`~rosaos.events.types.UserText`): the sentence is matched (:class:`~rosaos.intents.understanding.matching.
  IntentMatcher`). An exact match becomes one ``launch_process`` call per process, all in one
  response (parallel tool calls). Anything else becomes a text reply: a clarifying question, a
  refusal naming what exists, or "not understood". Nothing is launched on a guess.
- the ``launch_process`` results: a short acknowledgement from each plan ("On it: turn on the
  kitchen light."), or the refusal (an exclusive device held by another process) passed on.
- a :class:`~rosaos.events.callback.WorkerCallback`: the process's output (its plan made it a
  user-facing sentence), or an apology with the error; its plan's follow-up, if it has one.
- a :class:`~rosaos.events.types.DeviceNotice`: ``notify`` ones are said through the Reachy Mini (one process that calls its
  ``speak``); ``info`` ones get no reply (:mod:`rosaos.notices.notice_plan`).
- an :class:`~rosaos.events.types.ErrorReport`: acknowledged in one sentence.
- timers ("… in ten minutes", "what timers are set?", "cancel that timer") and a
  :class:`~rosaos.events.types.TimerFired`:
  :mod:`rosaos.timers.timer_turn`, asked first;
- "stop" however it is said, questions about a device's state and "what can you do?": the
  kernel's lease-free ``stop`` and ``device_state`` tools (:mod:`rosaos.models.kernel_actions`),
  asked next;
- memory ("remember this spot as the kitchen", "go to the kitchen", "call the dog Rex"):
  :mod:`rosaos.models.memory_turn`, asked after them; aliases people gave are resolved before any match.
"""

from __future__ import annotations

from collections.abc import Sequence

from pydantic import ValidationError
from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    ModelResponsePart,
    TextPart,
    ToolCallPart,
)
from pydantic_ai.models import Model, ModelRequestParameters
from pydantic_ai.settings import ModelSettings

from rosaos.events.callback import WorkerCallback
from rosaos.events.plan import Plan
from rosaos.events.types import DeviceNotice, ErrorReport, Event
from rosaos.intents.grammar.phrases import phrase, pronouns
from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.planning.follow_ups import callback_response, plan_follow_up
from rosaos.intents.understanding.matching import IntentMatcher, MatchResult
from rosaos.intents.understanding.stop_words import DeviceRefs
from rosaos.memory.memory_phrases import apply_preferences, resolve_aliases
from rosaos.memory.store import MemoryStore
from rosaos.models import kernel_actions
from rosaos.models.conversation import (
    ToolOutcome,
    callback_of,
    content_text,
    current_turn,
    last_command_devices,
    request_event,
    responses_by,
    said,
    tool_outcomes,
    turn_event,
)
from rosaos.models.memory_turn import is_memory_sentence, memory_turn
from rosaos.models.turn_outcome import marked, unmatched
from rosaos.notices.notice_plan import SILENCE, notice_response
from rosaos.timers.timer_turn import is_timer_sentence, timer_turn

LAUNCH_TOOL = "launch_process"
NO_OUTPUT = "(no output)"


class LocalIntentModel(Model):
    """The offline kernel model: sentence templates instead of an LLM.

    ``devices`` are the world's devices (:func:`rosaos.intents.grammar.vocabulary.device_vocabularies`);
    ``language`` is ``[models] language``. The hassil grammars are built here, once.
    """

    def __init__(
        self, devices: Sequence[DeviceVocabulary], language: str = "en", speaker: str | None = None
    ) -> None:
        super().__init__()
        self.language = language
        self.matcher = IntentMatcher(devices, language)
        self.devices = list(devices)
        self.refs = DeviceRefs(devices, language)
        """Device references for "stop" and state questions (:mod:`rosaos.models.kernel_actions`)."""
        self.speaker = speaker
        """The always-attached device that speaks to the user (the Reachy Mini), if any."""
        self.memory: MemoryStore | None = None
        """What people told rosaOS (aliases, places); the kernel sets it once its store is open."""

    @property
    def model_name(self) -> str:
        """The name responses carry; routing uses it to keep a turn on the model that began it."""
        return "rosaos-local-intent"

    @property
    def system(self) -> str:
        """The provider, for telemetry: rosaOS itself."""
        return "rosaos"

    def match(self, text: str, focus: frozenset[str] | None = None) -> MatchResult:
        """What ``text`` asks for: processes to launch, or the reply instead (see ``IntentMatcher``);
        ``focus`` limits it to those devices."""
        if self.memory is not None:  # "Rex, sit" means "the dog, sit" once someone said so
            text = resolve_aliases(text, self.memory.aliases())
            # "set my reading light" means the 40 % the user said they like it at
            text = apply_preferences(text, self.memory.preferences())
        return self.matcher.match(text, focus)

    def handles_event(self, event: Event) -> bool:
        """Whether this model answers ``event`` exactly, so an LLM is not needed.

        True for user text that matches completely and for callbacks of processes it planned.
        A bare choice ("the kitchen light") is not: it may answer the LLM's "which light?".
        """
        text = said(event)
        if text is not None:
            if is_timer_sentence(text, self.match) or is_memory_sentence(text, self.memory, self.match):
                return True
            if kernel_actions.handles(text, self.refs):
                return True
            return self.match(text).is_exact and not self.matcher.choice(text)
        callback = callback_of(event)
        return callback is not None and callback.plan is not None

    def handles(self, messages: Sequence[ModelMessage]) -> bool:
        """Whether this model should answer the request at the end of ``messages``."""
        turn = current_turn(messages)
        if len(turn) > 1:  # a turn already under way stays with the model that started it
            return responses_by(turn, self.model_name)
        event = turn_event(messages)
        return event is not None and self.handles_event(event)

    async def request(
        self,
        messages: list[ModelMessage],
        model_settings: ModelSettings | None,
        model_request_parameters: ModelRequestParameters,
    ) -> ModelResponse:
        """Answer the kernel event at the end of ``messages`` (see the module docstring)."""
        model_settings, model_request_parameters = self.prepare_request(
            model_settings, model_request_parameters
        )
        tools = [tool.name for tool in model_request_parameters.function_tools]
        return ModelResponse(parts=self.respond(messages, tools), model_name=self.model_name)

    def respond(self, messages: Sequence[ModelMessage], tools: Sequence[str]) -> list[ModelResponsePart]:
        """The response parts for ``messages``, given the names of the tools the agent offers."""
        timers = timer_turn(messages, tools, self.match, self._command, self._acknowledge)
        if timers is not None:  # set/list/cancel timers, or a [Timer fired] event's action
            return timers
        actions = kernel_actions.kernel_action_turn(
            messages, tools, self.refs, self.devices, self._command, self._acknowledge, self.match
        )
        if actions is not None:  # stop, a question about state, "what can you do?": no lease
            return actions
        memory = memory_turn(messages, tools, self.memory, self.match)
        if memory is not None:  # places, facts, aliases
            return memory
        event = turn_event(messages)
        callback = callback_of(event)
        outcomes = tool_outcomes(current_turn(messages))
        if outcomes:
            # A follow-up launched on a callback: say how the first process ended, then the ack.
            before = self._callback_reply(callback) + " " if callback is not None else ""
            return [TextPart(before + self._acknowledge(outcomes))]
        text = said(event)
        if text is not None:
            return self._command(text, tools, self._open_question(messages), last_command_devices(messages))
        if callback is not None:
            reply = self._callback_reply(callback)
            chained = callback_response(callback, _launch_tool(tools), reply)
            return chained or [TextPart(reply)]
        payload = event.payload if event is not None else None
        if isinstance(payload, DeviceNotice):
            return notice_response(payload, self.speaker, _launch_tool(tools))
        message = payload.message if isinstance(payload, ErrorReport) else str(payload)
        return [TextPart(phrase(self.language, "error", message=message))]

    def _open_question(self, messages: Sequence[ModelMessage]) -> str | None:
        """The user's previous sentence, if this model's last reply asked "which one?" about it."""
        earlier = list(messages[: len(messages) - len(current_turn(messages))])
        if (
            not earlier
            or not isinstance(earlier[-1], ModelResponse)
            or earlier[-1].model_name != self.model_name
        ):
            return None
        reply = earlier[-1].text or ""
        previous = said(request_event(_first_request(current_turn(earlier))))
        if previous is None:
            return None
        asked = self.match(previous)
        return previous if asked.kind == "clarify" and asked.reply == reply else None

    def _command(
        self,
        text: str,
        tools: Sequence[str],
        open_question: str | None = None,
        previous: frozenset[str] = frozenset(),
    ) -> list[ModelResponsePart]:
        # An answer to "which one?" ("the kitchen light") completes the question's sentence; on
        # its own it would read as "turn on the kitchen light".
        answered = self.matcher.follow_up(open_question, text) if open_question else None
        result = (
            answered
            or plan_follow_up(text, self.match, self.language, self.matcher.literal)
            or self.match(text)
        )
        if answered is None and previous:
            result = self._about_previous(text, result, previous)
        if not result.is_exact:  # nothing runs: say why, typed, for `rosaos chat --wait`
            return [marked(result.reply, unmatched(result))]
        launch = _launch_tool(tools)
        if launch is None:  # misconfigured agent: say so rather than pretend
            reason = f"no {LAUNCH_TOOL} tool is available"
            return [marked(phrase(self.language, "launch_refused", reason=reason), "refused")]
        return [ToolCallPart(launch, process.launch_args) for process in result.processes]

    def _about_previous(self, text: str, result: MatchResult, previous: frozenset[str]) -> MatchResult:
        """``text`` read as about the previous command's devices, when it names no device and
        either refers back ("make it green") or is not understood alone ("a bit dimmer than
        that" asks which one): the person means what they just acted on."""
        named, words = self.matcher.context.named_in(text)
        refers = bool(set(words) & (pronouns(self.language) | {"that", "this"}))
        if named or not (refers or not result.is_exact):
            return result
        focused = self.match(text, previous)
        return focused if focused.is_exact else result

    def _acknowledge(self, outcomes: list[ToolOutcome]) -> str:
        replies: list[str] = []
        for outcome in outcomes:
            if not outcome.ok:
                replies.append(phrase(self.language, "launch_refused", reason=content_text(outcome.content)))
                continue
            plan = _launched_plan(outcome.call)
            replies.append(
                plan.ack if plan is not None and plan.ack else phrase(self.language, "callback_done")
            )
        # "Turn off all the lights" launches one process per light, all with the same ack.
        return " ".join(dict.fromkeys(replies))

    def _callback_reply(self, callback: WorkerCallback) -> str:
        plan = callback.plan
        if callback.status == "ok":
            if plan is not None and plan.quiet:  # it only told the user something
                return SILENCE
            output = (callback.output or "").strip()
            return output if output and output != NO_OUTPUT else phrase(self.language, "callback_done")
        error = callback.error or callback.output or callback.status
        if plan is not None:
            return plan.failure.replace("{error}", error)
        return phrase(self.language, "callback_failed", status=callback.status, error=error)


def _launched_plan(call: ToolCallPart) -> Plan | None:
    """The plan this engine gave a ``launch_process`` call (JSON data in its arguments), if any."""
    try:
        return Plan.model_validate(call.args_as_dict().get("plan"))
    except ValidationError:  # none (an LLM's launch in the same history), or not a plan
        return None


def _launch_tool(tools: Sequence[str]) -> str | None:
    return next((name for name in tools if name == LAUNCH_TOOL), None) or next(
        (name for name in tools if name.endswith(LAUNCH_TOOL)), None
    )


def _first_request(messages: Sequence[ModelMessage]) -> ModelRequest | None:
    return next((message for message in messages if isinstance(message, ModelRequest)), None)
