"""The kernel loop: one event at a time, rendered for the model, handled, then acknowledged.

Delivery is at least once: an event is marked handled only after the kernel agent has finished
with it, so events left unhandled by a crash are handled after a restart, in order.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import Awaitable, Callable
from typing import Any

from pydantic_ai import Agent
from pydantic_ai.exceptions import UsageLimitExceeded
from pydantic_ai.messages import ModelMessage, RetryPromptPart, ToolCallPart, ToolReturnPart
from pydantic_ai.models import Model
from pydantic_ai.models.wrapper import WrapperModel
from pydantic_ai.toolsets import CombinedToolset
from pydantic_ai.usage import UsageLimits

from rosaos.events.types import Event, UserText
from rosaos.kernel.agent import trim_history
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.event_text import render_event, render_events
from rosaos.kernel.launch_cause import CurrentEvent
from rosaos.kernel.offline_turn import offline_turn
from rosaos.kernel.short_turns import LaunchAckModel, relayable, relayed_messages
from rosaos.kernel.updates import UpdateKind, UpdateStream
from rosaos.models.kernel_model import LocalIntentModel
from rosaos.models.tool_schemas import KERNEL_HIDDEN, CompactToolsModel
from rosaos.models.turn_outcome import turn_outcome

log = logging.getLogger(__name__)

MODEL_RETRIES = 3
"""Attempts per event when the model itself fails (network, rate limit) before giving up on it."""

MAX_DELIVERIES = 3
"""An event redelivered this often has crashed the kernel each time: report it and move on."""

BATCH_LIMIT = 20
"""Most events one LLM turn handles together (those that arrived while the model was thinking)."""

__all__ = ["KernelLoop", "Output", "render_event", "tool_activity"]


class KernelLoop:
    """Reads the event store and runs the kernel agent on each event, keeping its history."""

    def __init__(
        self,
        store: EventStore,
        updates: UpdateStream,
        agent: Agent[None, str],
        instructions: Callable[[], str],
        model: Callable[[Event], Model | None] = lambda event: None,
        history_budget: int = 40,
        request_limit: int = 20,
        current: CurrentEvent | None = None,
        history_chars: int = 4000,
        relay_reports: bool = True,
    ) -> None:
        self.store = store
        self.updates = updates
        self.agent = agent
        self.instructions = instructions
        self.model_for = model
        self.history_budget = history_budget
        self.history_chars = history_chars
        """The kernel's history is bounded by size too: a few long callbacks weigh like many turns."""
        self.relay_reports = relay_reports
        """Relay an ok process's report to the user without a model request (see short_turns)."""
        self.request_limit = request_limit
        self.history: list[ModelMessage] = []
        self.handled = 0
        self.current = current or CurrentEvent()
        """The event being handled: the cause of the launches its handling makes."""
        self.before: Callable[[Event], Awaitable[list[Output] | None]] | None = None
        """Sees each event before the model; outputs instead of a model run (confirmation answers)."""
        self._toolset = CombinedToolset(agent.toolsets)
        """The agent's tools, for turns of the offline engine that run without the agent."""

    async def run_forever(self) -> None:
        """Handle events until cancelled."""
        # One session with the kernel's tools for the loop's life, not one per event: opening it
        # was two thirds of handling a simple event.
        async with self.agent:
            while True:
                await self.run_pending()
                await self.store.wait_for_pending()

    async def run_pending(self) -> int:
        """Handle every pending event, oldest first; return how many were handled.

        Events for the LLM that arrived while it was thinking are handled together, in one turn
        with one request (up to :data:`BATCH_LIMIT`): a slow model does not make a queue of turns.
        The offline engine reads one event per turn and takes them one at a time.
        """
        count = 0
        while (event := await self.store.next_pending()) is not None:
            queue = [event]
            if self._for_model(event):
                queue += await self.store.take_pending(after=event.id, limit=BATCH_LIMIT - 1)
            while queue:
                batch = [queue.pop(0)]
                while queue and self._for_model(batch[0]) and self._for_model(queue[0]):
                    batch.append(queue.pop(0))
                # A batch's launches are caused by its first event: the offline engine's batches
                # hold one event, and an LLM batch is handled again whole after a crash.
                self.current.begin(batch[0].id, said=user_sentence(batch))
                try:
                    outputs = await self.handle_batch(batch)
                finally:
                    self.current.end()
                # The outputs and the acknowledgements commit together: after a crash an event
                # shows all of its outputs or none (and is then handled again).
                await self.updates.publish_batch_and_mark_handled([e.id for e in batch], outputs)
                self.handled += len(batch)
                count += len(batch)
        return count

    def reset_conversation(self) -> None:
        """Forget the kernel's conversation (a fresh start for benchmarks and tests)."""
        self.history = []

    def _for_model(self, event: Event) -> bool:
        """Whether ``event`` goes to an LLM (which can read several events in one turn)."""
        return not _is_offline_engine(self.model_for(event) or self.agent.model)

    async def handle(self, event: Event) -> list[Output]:
        """Run the kernel agent on one event; return the updates that say what it did."""
        return await self.handle_batch([event])

    async def handle_batch(self, events: list[Event]) -> list[Output]:
        """Run the kernel agent on ``events`` in one turn; return the updates that say what it did."""
        outputs: list[Output] = []
        for_model: list[Event] = []
        for event in events:
            if event.attempts > MAX_DELIVERIES:
                outputs.append(
                    _error(f"event {event.id} was skipped: handling it failed {event.attempts - 1} times")
                )
            elif self.before is not None and (answered := await self.before(event)) is not None:
                outputs += answered
            else:
                for_model.append(event)
        if for_model:
            outputs += await self._turn(for_model)
        return outputs

    async def _turn(self, events: list[Event]) -> list[Output]:
        prompt = render_events(events)
        model = self.model_for(events[0])
        offline = model or self.agent.model
        engine = _is_offline_engine(offline)
        if len(events) == 1 and not engine:
            report = relayable(events[0]) if self.relay_reports else None
            if report is not None:  # nothing to decide: the process's report is the reply
                self._remember(relayed_messages(prompt, report))
                return [("kernel_reply", report, {"relayed": True, "outcome": "done"})]
        for attempt in range(1, MODEL_RETRIES + 1):
            try:
                if engine:  # no agent run needed, and the engine reads the typed event: see offline_turn
                    assert isinstance(offline, Model) and len(events) == 1
                    turn = await offline_turn(
                        offline,
                        self._toolset,
                        events[0],
                        prompt,
                        history=self.history,
                        instructions=self.instructions(),
                        request_limit=self.request_limit,
                    )
                    new_messages, output = turn.new_messages, turn.output
                else:
                    llm = (
                        LaunchAckModel(CompactToolsModel(offline, KERNEL_HIDDEN))
                        if offline is not None
                        else None
                    )
                    result = await self.agent.run(
                        prompt,
                        message_history=self.history,
                        instructions=self.instructions(),
                        model=llm,
                        usage_limits=UsageLimits(request_limit=self.request_limit),
                    )
                    new_messages, output = result.new_messages(), result.output
            except UsageLimitExceeded as error:
                return [_error(f"the kernel gave up on this event: {error}")]
            except Exception as error:  # the model or its provider failed; try again, then report
                ids = ", ".join(str(event.id) for event in events)
                log.warning("kernel model failed on event %s (attempt %s): %s", ids, attempt, error)
                if attempt == MODEL_RETRIES:
                    return [_error(f"the kernel model failed: {type(error).__name__}: {error}")]
                await asyncio.sleep(0.5 * 2**attempt)
                continue
            break
        outputs = tool_activity(new_messages)
        # How the turn ended for what was asked, typed: `rosaos chat --wait` exits on it.
        outcome = turn_outcome(new_messages)
        if output.strip():
            outputs.append(("kernel_reply", output, {"outcome": outcome}))
        elif outcome != "done":  # a silent turn that did nothing still says so
            outputs.append(("notice", f"nothing was done ({outcome})", {"outcome": outcome}))
        self._remember(new_messages)
        return outputs

    def _remember(self, new_messages: list[ModelMessage]) -> None:
        self.history = trim_history([*self.history, *new_messages], self.history_budget, self.history_chars)


def user_sentence(events: list[Event]) -> str | None:
    """The user's words when ``events`` hold exactly one sentence of theirs; None otherwise.

    ``launch_process`` takes them as its task when the model gives none: when the sentence is the
    whole task, copying it costs a model its decoding (issue 22: 9 of a light switch's 28 tokens)."""
    said = [event.payload.text for event in events if isinstance(event.payload, UserText)]
    return said[0] if len(said) == 1 else None


def _is_offline_engine(model: object) -> bool:
    """Whether ``model`` is the offline engine, also inside wrappers (the bench counts its requests)."""
    while isinstance(model, WrapperModel):
        model = model.wrapped
    return isinstance(model, LocalIntentModel)


Output = tuple[UpdateKind, str, dict[str, Any]]
"""One update the kernel publishes for an event: kind, text, data."""


def _error(message: str) -> Output:
    log.error(message)
    return ("error", message, {})


def tool_activity(messages: list[ModelMessage]) -> list[Output]:
    """Every kernel tool call, and every process it launched or was refused, as updates.

    Taken from the run's messages (not from inside the tools) so each update carries the id of
    the event that caused it; ``rosaos chat --wait`` follows that thread.
    """
    outputs: list[Output] = []
    for message in messages:
        for part in message.parts:
            if isinstance(part, ToolCallPart):
                text = f"{part.tool_name}({part.args_as_json_str()})"
                outputs.append(("tool_call", text, {"tool": part.tool_name, "args": part.args_as_dict()}))
            elif isinstance(part, ToolReturnPart) and part.tool_name == "stop":
                outputs += _stop_activity(part)
            elif isinstance(part, ToolReturnPart) and part.tool_name == "launch_process":
                if part.outcome != "success":
                    text = f"launch refused: {part.model_response_str()}"
                    outputs.append(("notice", text, {"refused": "launch_process"}))
                    continue
                launched = _as_dict(part.content)
                if "process_id" in launched:
                    devices = ", ".join(launched.get("devices", [])) or "no devices"
                    text = f"process {launched['process_id']} launched with {devices}"
                    outputs.append(("process_launched", text, launched))
            elif isinstance(part, RetryPromptPart) and part.tool_name in ("launch_process", "stop"):
                what = "launch" if part.tool_name == "launch_process" else "stop"
                outputs.append(
                    ("notice", f"{what} refused: {part.model_response()}", {"refused": part.tool_name})
                )
    return outputs


def _stop_activity(part: ToolReturnPart) -> list[Output]:
    """A failed stop, or one whose device did not confirm its safe_stop, as a notice that says so.

    ``rosaos chat --wait`` reads ``refused`` in its data: what was asked was not (surely) done.
    """
    if part.outcome != "success":
        return [("notice", f"stop refused: {part.model_response_str()}", {"refused": "stop"})]
    report = _as_dict(part.content)
    unconfirmed = [
        d["device"] for d in report.get("devices", []) if isinstance(d, dict) and not d.get("safe_stop")
    ]
    if not unconfirmed:
        return []
    text = f"stop NOT confirmed on {', '.join(unconfirmed)}: see the reply"
    return [("notice", text, {"refused": "stop", "devices": unconfirmed})]


def _as_dict(content: Any) -> dict[str, Any]:
    """A tool return's content as a dict (MCP results may arrive as JSON text)."""
    if isinstance(content, dict):
        return content
    if isinstance(content, str):
        try:
            value = json.loads(content)
        except ValueError:
            return {}
        return value if isinstance(value, dict) else {}
    return {}
