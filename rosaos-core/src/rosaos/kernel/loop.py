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
from pydantic_ai.toolsets import CombinedToolset
from pydantic_ai.usage import UsageLimits

from rosaos.kernel.agent import trim_history
from rosaos.kernel.events import Event, EventStore
from rosaos.kernel.launch_cause import CurrentEvent
from rosaos.kernel.notice_text import render_notice
from rosaos.kernel.offline_turn import offline_turn
from rosaos.kernel.timer_text import render_timer_fired
from rosaos.kernel.updates import UpdateKind, UpdateStream
from rosaos.models.kernel_model import LocalIntentModel
from rosaos.receipts import receipts_text

log = logging.getLogger(__name__)

MODEL_RETRIES = 3
"""Attempts per event when the model itself fails (network, rate limit) before giving up on it."""

MAX_DELIVERIES = 3
"""An event redelivered this often has crashed the kernel each time: report it and move on."""


def render_event(event: Event) -> str:
    """The text the kernel model reads for an event, tagged by kind."""
    payload: Any = event.payload
    match event.kind:
        case "user_said":
            return f"[User said] {payload.text}"
        case "user_typed":
            return f"[User typed] {payload.text}"
        case "worker_callback":
            head = f"[Worker callback] worker={payload.process_id} status={payload.status}"
            if payload.task:
                head += f" task={payload.task!r}"
            body = (
                f"error: {payload.error}" if payload.error else f"output: {payload.output or '(no output)'}"
            )
            if payload.receipts:  # what was really done, whatever the output claims
                body += "\n" + receipts_text(payload.receipts)
            return f"{head}\n{body}"
        case "device_notice":
            return render_notice(payload)
        case "error":
            return f"[Error] {payload.message}"
        case "timer_fired":
            return render_timer_fired(payload)
    return f"[{event.kind}] {payload}"


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
    ) -> None:
        self.store = store
        self.updates = updates
        self.agent = agent
        self.instructions = instructions
        self.model_for = model
        self.history_budget = history_budget
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
        """Handle every pending event, oldest first; return how many were handled."""
        count = 0
        while (event := await self.store.next_pending()) is not None:
            self.current.begin(event.id)
            try:
                outputs = await self.handle(event)
            finally:
                self.current.end()
            # The outputs and the acknowledgement commit together: after a crash an event shows
            # all of its outputs or none (and is then handled again).
            await self.updates.publish_and_mark_handled(event.id, outputs)
            self.handled += 1
            count += 1
        return count

    def reset_conversation(self) -> None:
        """Forget the kernel's conversation (a fresh start for benchmarks and tests)."""
        self.history = []

    async def handle(self, event: Event) -> list[Output]:
        """Run the kernel agent on one event; return the updates that say what it did."""
        if event.attempts > MAX_DELIVERIES:
            return [_error(f"event {event.id} was skipped: handling it failed {event.attempts - 1} times")]
        if self.before is not None and (outputs := await self.before(event)) is not None:
            return outputs
        prompt = render_event(event)
        model = self.model_for(event)
        offline = model or self.agent.model
        for attempt in range(1, MODEL_RETRIES + 1):
            try:
                if isinstance(offline, LocalIntentModel):  # no agent run needed: see offline_turn
                    turn = await offline_turn(
                        offline,
                        self._toolset,
                        prompt,
                        history=self.history,
                        instructions=self.instructions(),
                        request_limit=self.request_limit,
                    )
                    new_messages, output = turn.new_messages, turn.output
                else:
                    result = await self.agent.run(
                        prompt,
                        message_history=self.history,
                        instructions=self.instructions(),
                        model=model,
                        usage_limits=UsageLimits(request_limit=self.request_limit),
                    )
                    new_messages, output = result.new_messages(), result.output
            except UsageLimitExceeded as error:
                return [_error(f"the kernel gave up on this event: {error}")]
            except Exception as error:  # the model or its provider failed; try again, then report
                log.warning("kernel model failed on event %s (attempt %s): %s", event.id, attempt, error)
                if attempt == MODEL_RETRIES:
                    return [_error(f"the kernel model failed: {type(error).__name__}: {error}")]
                await asyncio.sleep(0.5 * 2**attempt)
                continue
            break
        outputs = tool_activity(new_messages)
        if output.strip():
            outputs.append(("kernel_reply", output, {}))
        self.history = trim_history([*self.history, *new_messages], self.history_budget)
        return outputs


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
