"""The kernel agent's offline model: the local-intent engine as a pydantic-ai ``Model``.

Plugged in where an LLM would be, so the kernel runs unchanged: same queue, same
``launch_process``, same workers, leases and MCP tools. Per request it reads the event being
handled (see :func:`rosaos.kernel.loop.render_event`) and answers:

- ``[User said]`` / ``[User typed]``: the sentence is matched (:class:`~rosaos.intents.understanding.matching.
  IntentMatcher`). An exact match becomes one ``launch_process`` call per process, all in one
  response (parallel tool calls). Anything else becomes a text reply: a clarifying question, a
  refusal naming what exists, or "not understood". Nothing is launched on a guess.
- the ``launch_process`` results: a short acknowledgement from each plan ("On it: turn on the
  kitchen light."), or the refusal (an exclusive device held by another process) passed on.
- ``[Worker callback]``: the process's output (its plan made it a user-facing sentence), or an
  apology with the error. No new process.
- ``[Device notice]``: ``notify`` ones are said through the Reachy Mini (one process that calls its
  ``speak``); ``info`` ones get no reply (:mod:`rosaos.intents.planning.notice_plan`).
- ``[Error]``: acknowledged in one sentence.
- timers ("… in ten minutes", "what timers are set?", "cancel that timer") and ``[Timer fired]``:
  :mod:`rosaos.intents.planning.timer_plan`, asked first;
- "stop" however it is said, questions about a device's state and "what can you do?": the
  kernel's lease-free ``stop`` and ``device_state`` tools (:mod:`rosaos.models.kernel_actions`),
  asked next;
- memory ("remember this spot as the kitchen", "go to the kitchen", "call the dog Rex"):
  :mod:`rosaos.memory.turn`, asked after them; aliases people gave are resolved before any match.
"""

from __future__ import annotations

from collections.abc import Sequence

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

from rosaos.intents.grammar.phrases import phrase
from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.planning.followups import callback_response, plan_follow_up
from rosaos.intents.planning.notice_plan import SILENCE, notice_response
from rosaos.intents.planning.plan import PlanError, decode_plan, has_plan
from rosaos.intents.planning.timer_plan import is_timer_sentence, timer_turn
from rosaos.intents.understanding.matching import IntentMatcher, MatchResult
from rosaos.intents.understanding.stop_words import DeviceRefs
from rosaos.memory.memory_phrases import resolve_aliases
from rosaos.memory.store import MemoryStore
from rosaos.memory.turn import is_memory_sentence, memory_turn
from rosaos.models import kernel_actions
from rosaos.models.conversation import (
    ToolOutcome,
    content_text,
    current_turn,
    last_request,
    parse_callback,
    parse_event,
    responses_by,
    tool_outcomes,
    user_text,
)

LAUNCH_TOOL = "launch_process"
USER_TAGS = frozenset({"User said", "User typed"})
CALLBACK_TAG = "Worker callback"
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

    def match(self, text: str) -> MatchResult:
        """What ``text`` asks for: processes to launch, or the reply instead (see ``IntentMatcher``)."""
        if self.memory is not None:  # "Rex, sit" means "the dog, sit" once someone said so
            text = resolve_aliases(text, self.memory.aliases())
        return self.matcher.match(text)

    def handles_text(self, rendered_event: str) -> bool:
        """Whether this model answers ``rendered_event`` exactly, so an LLM is not needed.

        True for user text that matches completely and for callbacks of processes it planned.
        A bare choice ("the kitchen light") is not: it may answer the LLM's "which light?".
        """
        event = parse_event(rendered_event)
        if (event.tag in USER_TAGS or event.tag is None) and (
            is_timer_sentence(event.body, self.match)
            or is_memory_sentence(event.body, self.memory, self.match)
        ):
            return True
        if (event.tag in USER_TAGS or event.tag is None) and kernel_actions.handles(event.body, self.refs):
            return True
        if event.tag in USER_TAGS or event.tag is None:
            return self.match(event.body).is_exact and not self.matcher.choice(event.body)
        if event.tag == CALLBACK_TAG:
            task = parse_callback(event.body).task
            return task is not None and has_plan(task)
        return False

    def handles(self, messages: Sequence[ModelMessage]) -> bool:
        """Whether this model should answer the request at the end of ``messages``."""
        turn = current_turn(messages)
        if len(turn) > 1:  # a turn already under way stays with the model that started it
            return responses_by(turn, self.model_name)
        text = user_text(last_request(messages))
        return text is not None and self.handles_text(text)

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
        turn = current_turn(messages)
        outcomes = tool_outcomes(turn)
        if outcomes:
            # A follow-up launched on a callback: say how the first process ended, then the ack.
            started = parse_event(user_text(_first_request(turn)) or "")
            before = self._callback_reply(started.body) + " " if started.tag == CALLBACK_TAG else ""
            return [TextPart(before + self._acknowledge(outcomes))]
        event = parse_event(user_text(last_request(messages)) or "")
        if event.tag in USER_TAGS or event.tag is None:
            return self._command(event.body, tools, self._open_question(messages))
        if event.tag == CALLBACK_TAG:
            reply = self._callback_reply(event.body)
            chained = callback_response(parse_callback(event.body), _launch_tool(tools), reply)
            return chained or [TextPart(reply)]
        if event.tag == "Device notice":
            return notice_response(event.body, self.speaker, _launch_tool(tools))
        return [TextPart(phrase(self.language, "error", message=event.body))]

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
        previous = parse_event(user_text(_first_request(current_turn(earlier))) or "")
        if previous.tag not in USER_TAGS and previous.tag is not None:
            return None
        asked = self.match(previous.body)
        return previous.body if asked.kind == "clarify" and asked.reply == reply else None

    def _command(
        self, text: str, tools: Sequence[str], open_question: str | None = None
    ) -> list[ModelResponsePart]:
        # An answer to "which one?" ("the kitchen light") completes the question's sentence; on
        # its own it would read as "turn on the kitchen light".
        answered = self.matcher.follow_up(open_question, text) if open_question else None
        literal = getattr(self.matcher, "_literal", None)  # the engine's reading as said, if it has one
        result = answered or plan_follow_up(text, self.match, self.language, literal) or self.match(text)
        if not result.is_exact:
            return [TextPart(result.reply)]
        launch = _launch_tool(tools)
        if launch is None:  # misconfigured agent: say so rather than pretend
            return [
                TextPart(
                    phrase(self.language, "launch_refused", reason=f"no {LAUNCH_TOOL} tool is available")
                )
            ]
        return [
            ToolCallPart(launch, {"task": process.task, "devices": list(process.devices)})
            for process in result.processes
        ]

    def _acknowledge(self, outcomes: list[ToolOutcome]) -> str:
        replies: list[str] = []
        for outcome in outcomes:
            if not outcome.ok:
                replies.append(phrase(self.language, "launch_refused", reason=content_text(outcome.content)))
                continue
            task = str(outcome.call.args_as_dict().get("task", ""))
            try:
                plan = decode_plan(task)
            except PlanError:
                plan = None
            replies.append(
                plan.ack if plan is not None and plan.ack else phrase(self.language, "callback_done")
            )
        # "Turn off all the lights" launches one process per light, all with the same ack.
        return " ".join(dict.fromkeys(replies))

    def _callback_reply(self, body: str) -> str:
        callback = parse_callback(body)
        if callback.status == "ok":
            if _quiet(callback.task):
                return SILENCE
            output = (callback.output or "").strip()
            return output if output and output != NO_OUTPUT else phrase(self.language, "callback_done")
        error = callback.error or callback.output or callback.status
        try:
            plan = decode_plan(callback.task or "")
        except PlanError:
            plan = None
        if plan is not None:
            return plan.failure.replace("{error}", error)
        return phrase(self.language, "callback_failed", status=callback.status, error=error)


def _quiet(task: str | None) -> bool:
    """Whether the callback's plan asks for no reply (it only told the user something)."""
    try:
        plan = decode_plan(task or "")
    except PlanError:
        return False
    return plan is not None and plan.quiet


def _launch_tool(tools: Sequence[str]) -> str | None:
    return next((name for name in tools if name == LAUNCH_TOOL), None) or next(
        (name for name in tools if name.endswith(LAUNCH_TOOL)), None
    )


def _first_request(messages: Sequence[ModelMessage]) -> ModelRequest | None:
    return next((message for message in messages if isinstance(message, ModelRequest)), None)
