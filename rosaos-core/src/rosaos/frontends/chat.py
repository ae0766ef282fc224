"""``rosaos chat``: a REPL against the running kernel, and a one-shot mode for scripts.

Both follow the updates stream by polling ``GET /updates?after=``: simple, resumable, and quick
enough at 10 Hz for a human or a script.
"""

from __future__ import annotations

import asyncio
import json
import re
import sys
import time
import uuid
from dataclasses import dataclass, field
from typing import Any

from rich.console import Console

from rosaos.cli.console import console as terminal
from rosaos.config import ConfigError
from rosaos.events.reply_outcome import TurnOutcome, as_outcome
from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable

POLL_SECONDS = 0.1

EXIT_OK = 0
EXIT_FAILED = 1
"""Something asked for failed or was refused: a launch, a stop, a process, a device or value the
world has not (the kernel's ``refused`` outcome)."""
EXIT_UNAVAILABLE = 2
EXIT_TIMEOUT = 3
EXIT_NOT_DONE = 4
"""Nothing was done because the kernel did not understand, or asked a question ("which one?",
"Did you mean …?") that waits for the user's answer."""

_WHY: dict[TurnOutcome, str] = {
    "refused": "nothing was done: the reply says what this world lacks; name a device, value or "
    "place it has (`rosaos devices list`)",
    "not_understood": "nothing was done: the message was not understood; say it another way "
    '(`rosaos chat -m "what can you do?"` gives examples)',
    "needs_answer": "nothing was done yet: the reply asks a question; answer it with another "
    "`rosaos chat -m …`, or send the whole command again more precisely",
    "needs_confirmation": 'nothing was done yet: the reply asks "Did you mean …?"; answer with '
    "`rosaos chat -m yes --wait` to run it, or send the command again as suggested",
}

_STYLE = {
    "kernel_reply": "bold green",
    "error": "bold red",
    "process_launched": "cyan",
    "process_ended": "cyan",
    "notice": "yellow",
}


# ESC/CSI sequences (colours, cursor moves, OSC titles and links) and other C0/C1 controls but
# newline and tab: text from devices and models must not drive the user's terminal.
_TERMINAL_CONTROLS = re.compile(
    r"\x1b\][^\x07\x1b]*(?:\x07|\x1b\\)?|\x1b\[[0-?]*[ -/]*[@-~]|\x1b.?|[\x00-\x08\x0b-\x1f\x7f-\x9f]"
)


def printable(text: str) -> str:
    """``text`` with terminal escape sequences and control characters removed."""
    return _TERMINAL_CONTROLS.sub("", text)


def format_update(update: dict[str, Any]) -> str | None:
    """The line a chat shows for an update, or None for updates a chat hides. Never raw escapes."""
    kind = update["kind"]
    text = printable(str(update["text"]))
    if kind == "kernel_reply":
        return f"rosaos: {text}"
    if kind in ("process_launched", "process_ended", "notice", "error"):
        return f"  · {text}"
    data = update.get("data", {})
    if kind == "event" and data.get("kind") == "worker_callback":
        return f"  · {_callback_line(data.get('payload', {}))}"
    if kind == "event" and data.get("kind") == "device_notice":
        return f"  · {text}"
    return None


def _callback_line(payload: dict[str, Any]) -> str:
    """A process's report in words: the ``[Process callback] process=1 status=ok`` header is for models."""
    said = printable(str(payload.get("error") or payload.get("output") or "")).strip()
    verb = "reported" if payload.get("status") == "ok" else f"ended {payload.get('status', 'unknown')}"
    return f"process {payload.get('process_id', '?')} {verb}" + (f": {said}" if said else "")


@dataclass
class Conversation:
    """What one message set in motion: its event, the processes it launched, their callbacks."""

    event_id: int
    replies: list[str] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    refusals: list[str] = field(default_factory=list)
    """Kernel tool calls refused for this message (a launch on a held device): not done."""
    outcomes: list[TurnOutcome] = field(default_factory=list)
    """How each kernel turn of this conversation ended (the typed ``outcome`` of its reply)."""
    processes: dict[int, dict[str, Any]] = field(default_factory=dict)
    callback_events: dict[int, int] = field(default_factory=dict)
    """callback event id → process id"""
    joined: set[int] = field(default_factory=set)
    """Events the kernel handled in the same turn as this message (their outputs are its outputs)."""
    unclaimed: dict[int, tuple[int, dict[str, Any]]] = field(default_factory=dict)
    """Callbacks seen before the launch that explains them: process id → (event id, payload).
    A fast worker can report before the kernel has finished the run that launched it."""

    def absorb(self, update: dict[str, Any]) -> bool:
        """Take in one update; True if it belongs to this conversation."""
        kind, event_id, data = update["kind"], update.get("event_id"), update.get("data") or {}
        if kind == "event" and data.get("kind") == "worker_callback" and event_id is not None:
            payload = data.get("payload", {})
            # Events stored before the rename carry ``worker_id``.
            process_id = int(payload.get("process_id", payload.get("worker_id", 0)))
            if process_id in self.processes:
                self._claim(process_id, event_id, payload)
                return True
            self.unclaimed[process_id] = (event_id, payload)
            return False
        if kind == "notice" and data.get("process_id") in self.processes:
            return True  # a question one of our processes asks (a confirmation) is ours to show
        if kind == "notice" and "handled_with" in data and event_id == self.event_id:
            # The kernel read this message together with later ones: their turn is ours too.
            self.joined.add(int(data["handled_with"]))
            return False
        ours = event_id == self.event_id or event_id in self.callback_events or event_id in self.joined
        if not ours:
            return False
        if kind == "notice" and data.get("refused"):
            self.refusals.append(update["text"])  # a refused launch, a stop not confirmed
        if kind in ("kernel_reply", "notice") and (outcome := as_outcome(data.get("outcome"))) is not None:
            self.outcomes.append(outcome)
        if kind == "process_launched" and "process_id" in data:
            process_id = int(data["process_id"])
            self.processes.setdefault(process_id, {})
            if process_id in self.unclaimed:
                self._claim(process_id, *self.unclaimed.pop(process_id))
        elif kind == "kernel_reply":
            self.replies.append(update["text"])
        elif kind == "error":
            self.errors.append(update["text"])
        return True

    def _claim(self, process_id: int, event_id: int, payload: dict[str, Any]) -> None:
        self.processes[process_id] = payload
        self.callback_events[event_id] = process_id

    @property
    def outcome(self) -> TurnOutcome:
        """The first turn that did nothing decides (later turns answer callbacks); else ``done``."""
        return next((outcome for outcome in self.outcomes if outcome != "done"), "done")

    @property
    def succeeded(self) -> bool:
        return self.exit_code == EXIT_OK

    @property
    def exit_code(self) -> int:
        """``EXIT_FAILED`` if anything asked for failed or was refused, ``EXIT_NOT_DONE`` if
        nothing was done for want of understanding or an answer, else ``EXIT_OK``."""
        statuses = [p.get("status") for p in self.processes.values()]
        if self.errors or self.refusals or any(status != "ok" for status in statuses):
            return EXIT_FAILED
        if self.outcome == "refused":
            return EXIT_FAILED
        return EXIT_NOT_DONE if self.outcome != "done" else EXIT_OK

    def reason(self) -> str | None:
        """One line for stderr: why the exit code is not 0, and what would work; None if it is 0."""
        failed = {pid: p["status"] for pid, p in self.processes.items() if p.get("status") != "ok"}
        if self.errors:
            return f"the kernel reported an error: {printable(self.errors[-1])}"
        if self.refusals:
            return f"{printable(self.refusals[0])} (`rosaos ps` lists what holds each device)"
        if failed:
            pid, status = next(iter(failed.items()))
            return f"process {pid} ended {status}; `rosaos log --process {pid}` shows its tool calls"
        return _WHY.get(self.outcome)

    def summary(self) -> dict[str, Any]:
        return {
            "event_id": self.event_id,
            "ok": self.succeeded,
            "outcome": self.outcome,
            "replies": self.replies,
            "errors": self.errors,
            "refusals": self.refusals,
            "processes": [{"id": pid, **info} for pid, info in self.processes.items()],
        }


async def _handled(client: KernelClient, event_id: int) -> bool:
    return bool((await client.event(event_id)).get("handled"))


async def send_and_wait(
    client: KernelClient, text: str, timeout: float, console: Console | None
) -> tuple[int, Conversation]:
    """Send ``text`` and follow it until it and every process it launched are handled."""
    cursor = await client.last_update_id()
    conversation = Conversation(await client.chat(text, idempotency_key=f"chat-{uuid.uuid4()}"))
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        # Check first, read second: an event's outputs commit with its "handled" mark, so updates
        # read after seeing it handled include every process it launched.
        was_settled = await _settled(client, conversation)
        known = len(conversation.processes), len(conversation.joined)
        updates, cursor = await client.updates_after(cursor)
        for update in updates:
            if conversation.absorb(update) and console is not None:
                line = format_update(update)
                if line:
                    console.print(line, style=_STYLE.get(update["kind"]), markup=False, highlight=False)
        if was_settled and (len(conversation.processes), len(conversation.joined)) == known:
            return conversation.exit_code, conversation
        await asyncio.sleep(POLL_SECONDS)
    conversation.errors.append(f"gave up waiting after {timeout:g} s")
    return EXIT_TIMEOUT, conversation


async def _settled(client: KernelClient, conversation: Conversation) -> bool:
    """The message, every process it launched, and every callback are handled by the kernel."""
    if not await _handled(client, conversation.event_id):
        return False
    if any(not info.get("status") for info in conversation.processes.values()):
        return False
    for event_id in [*conversation.callback_events, *conversation.joined]:
        if not await _handled(client, event_id):
            return False
    return True


async def one_shot(client: KernelClient, text: str, wait: bool, timeout: float, json_output: bool) -> int:
    """``rosaos chat -m TEXT [--wait]``."""
    console = None if json_output else terminal()
    if not wait:
        event_id = await client.chat(text, idempotency_key=f"chat-{uuid.uuid4()}")
        if json_output:
            print(json.dumps({"event_id": event_id}))
        else:
            print(f"sent as event {event_id}")
        return EXIT_OK
    code, conversation = await send_and_wait(client, text, timeout, console)
    if json_output:
        print(json.dumps(conversation.summary(), indent=2, default=str))
    reason = conversation.errors[-1] if code == EXIT_TIMEOUT else conversation.reason()
    if reason is not None:
        print(f"rosaos chat: {printable(reason)}", file=sys.stderr)
    return code


async def repl(client: KernelClient) -> int:
    """Interactive chat: type lines, see replies and callbacks as they come. Ctrl-D or /quit exits."""
    console = terminal()
    health = await client.health()
    console.print(f"Connected to rosaOS {health['version']} at {client.base_url} (model: {health['model']}).")
    if health.get("model_notice"):
        console.print(health["model_notice"], style="yellow", markup=False)
    console.print("Type a message; /ps lists processes; /quit or Ctrl-D leaves.", style="dim")
    cursor = await client.last_update_id()

    async def follow() -> None:
        nonlocal cursor
        while True:
            updates, cursor = await client.updates_after(cursor)
            for update in updates:
                line = format_update(update)
                if line:
                    console.print(line, style=_STYLE.get(update["kind"]), markup=False, highlight=False)
            await asyncio.sleep(POLL_SECONDS)

    follower = asyncio.create_task(follow())
    try:
        while True:
            try:
                line = await asyncio.to_thread(input, "you> ")
            except EOFError:
                return EXIT_OK
            line = line.strip()
            if not line:
                continue
            if line in ("/quit", "/exit"):
                return EXIT_OK
            if line == "/ps":
                for process in await client.processes():
                    console.print(f"  {process['id']:>4} {process['state']:<10} {process['task'][:60]}")
                continue
            await client.chat(line, idempotency_key=f"chat-{uuid.uuid4()}")
    finally:
        follower.cancel()


def chat_command(
    client_factory: Any, message: str | None, wait: bool, timeout: float, json_output: bool
) -> int:
    """Entry point for the CLI: builds the client, runs REPL or one-shot, maps errors to exit codes."""

    async def run() -> int:
        async with client_factory() as client:
            if message is None:
                return await repl(client)
            return await one_shot(client, message, wait, timeout, json_output)

    try:
        return asyncio.run(run())
    except (KernelUnavailable, ConfigError) as error:
        print(f"rosaos chat: {error}", file=sys.stderr)
        return EXIT_UNAVAILABLE
