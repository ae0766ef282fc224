"""Confirmation before risky actuation: a process pauses until a person says yes.

Config names what needs a yes (:func:`~rosaos.confirmations.confirming.confirm_rule`, beside the
worker's toolset that applies it): per device, ``confirm = ["drive",
"move_distance"]`` or ``confirm = "destructive"`` (every tool annotated ``destructiveHint``) or
``"off"``; globally, a top-level ``confirm``; by default, ``destructive`` for the ``real`` backend
of a driver that asks for it (``DriverSpec.confirm_on_real``, the ROS driver) and off otherwise.

A worker that reaches such a call posts it to ``POST /confirmations`` and waits on
``GET /confirmations/{id}?wait=``. The kernel asks on the updates stream (chat, web page) and by
voice; "yes" or "no" typed or said while a question is pending answers it (the kernel loop hands
the sentence here before the model sees it), as does ``POST /confirmations/{id}``. Silence for
``[kernel] confirm_timeout`` seconds is a no. On a no the worker ends the process, which releases
its leases.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import re
import time
from collections.abc import Awaitable, Callable
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

ConfirmState = Literal["pending", "yes", "no", "expired"]

KEEP_ANSWERED = 50
_YES = re.compile(r"^(yes|yeah|yep|sure|ok(ay)?|go( ahead)?|do it|confirm(ed)?|oui)\b", re.IGNORECASE)
_NO = re.compile(r"^(no|nope|don'?t|do not|stop|cancel|abort|non)\b", re.IGNORECASE)


def question(device: str, tool: str, arguments: dict[str, Any]) -> str:
    """The question for the person: "The turtlebot will move distance (meters 2). Go ahead?"."""
    action = tool.replace("_", " ")
    details = ", ".join(f"{key.replace('_', ' ')} {value}" for key, value in arguments.items())
    return f"The {device} will {action}{f' ({details})' if details else ''}. Go ahead?"


def read_answer(text: str) -> Literal["yes", "no"] | None:
    """ "yes"/"no" when the sentence is an answer (starts with one), else None."""
    cleaned = text.strip().strip(".!?,").strip()
    if _YES.match(cleaned):
        return "yes"
    if _NO.match(cleaned):
        return "no"
    return None


class ConfirmationRequest(BaseModel):
    """``POST /confirmations``: a worker asks before a call (its process id and the call)."""

    model_config = ConfigDict(extra="forbid")

    process_id: int = Field(ge=1)
    device: str = Field(min_length=1, max_length=100)
    tool: str = Field(min_length=1, max_length=100)
    arguments: dict[str, Any] = Field(default_factory=dict)


class ConfirmationAnswer(BaseModel):
    """``POST /confirmations/{id}``: a person's answer."""

    model_config = ConfigDict(extra="forbid")

    answer: Literal["yes", "no"]


class Confirmation(BaseModel):
    """One question and its state (``GET /confirmations``)."""

    id: int
    process_id: int
    device: str
    tool: str
    arguments: dict[str, Any]
    question: str
    state: ConfirmState
    created: float = Field(description="Seconds since the epoch.")
    expires: float = Field(description="When silence counts as no (epoch seconds).")
    answered_by: str | None = None


class ConfirmationList(BaseModel):
    """``GET /confirmations``: the pending questions (``?all=true`` adds recent answered ones)."""

    confirmations: list[Confirmation]


Announce = Callable[[Confirmation], Awaitable[None]]


class ConfirmationDesk:
    """The kernel's pending questions, in memory: a process that waits dies with the kernel anyway."""

    def __init__(
        self, timeout: float, announce: Announce | None = None, record: Announce | None = None
    ) -> None:
        self.timeout = timeout
        self._announce = announce
        self._record = record
        """Told of every question when asked and when settled (yes, no, expired): the safety log."""
        self._tasks: set[asyncio.Future[None]] = set()
        self._ids = itertools.count(1)
        self._items: dict[int, Confirmation] = {}
        self._changed: dict[int, asyncio.Event] = {}
        self._timers: dict[int, asyncio.TimerHandle] = {}

    async def ask(self, request: ConfirmationRequest) -> Confirmation:
        """Open a question; it expires after :attr:`timeout` seconds without an answer."""
        now = time.time()
        item = Confirmation(
            id=next(self._ids),
            process_id=request.process_id,
            device=request.device,
            tool=request.tool,
            arguments=request.arguments,
            question=question(request.device, request.tool, request.arguments),
            state="pending",
            created=now,
            expires=now + self.timeout,
        )
        self._items[item.id] = item
        self._changed[item.id] = asyncio.Event()
        loop = asyncio.get_running_loop()
        self._timers[item.id] = loop.call_later(self.timeout, self._settle, item.id, "expired", "silence")
        self._forget_old()
        if self._record is not None:
            await self._record(item)
        if self._announce is not None:
            await self._announce(item)
        return item

    def get(self, confirmation_id: int) -> Confirmation:
        """A question by id; ``KeyError`` when unknown."""
        return self._items[confirmation_id]

    def pending(self) -> list[Confirmation]:
        """The questions still waiting, oldest first."""
        return [item for item in self._items.values() if item.state == "pending"]

    def all(self) -> list[Confirmation]:
        """Every remembered question, oldest first."""
        return list(self._items.values())

    def answer(self, confirmation_id: int, answer: Literal["yes", "no"], by: str) -> Confirmation:
        """Answer a question; ``KeyError`` when unknown, ``ValueError`` when already settled."""
        item = self._items[confirmation_id]
        if item.state != "pending":
            raise ValueError(f"confirmation {confirmation_id} is already {item.state}")
        self._settle(confirmation_id, answer, by)
        return self._items[confirmation_id]

    def answer_oldest(self, text: str, by: str) -> Confirmation | None:
        """Answer the oldest pending question with a sentence, if it is a yes or a no."""
        pending = self.pending()
        answer = read_answer(text) if pending else None
        if answer is None:
            return None
        return self.answer(pending[0].id, answer, by)

    async def wait(self, confirmation_id: int, seconds: float) -> Confirmation:
        """The question once settled, or as it is after ``seconds``."""
        item = self._items[confirmation_id]
        if item.state == "pending":
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(seconds):
                    await self._changed[confirmation_id].wait()
        return self._items[confirmation_id]

    def _settle(self, confirmation_id: int, state: ConfirmState, by: str) -> None:
        item = self._items.get(confirmation_id)
        if item is None or item.state != "pending":
            return
        self._items[confirmation_id] = item.model_copy(update={"state": state, "answered_by": by})
        timer = self._timers.pop(confirmation_id, None)
        if timer is not None:
            timer.cancel()
        self._changed[confirmation_id].set()
        if self._record is not None:  # called from a timer too: record in a task of its own
            task: asyncio.Future[None] = asyncio.ensure_future(self._record(self._items[confirmation_id]))
            self._tasks.add(task)
            task.add_done_callback(self._tasks.discard)

    def _forget_old(self) -> None:
        settled = [key for key, item in self._items.items() if item.state != "pending"]
        for key in settled[: max(0, len(settled) - KEEP_ANSWERED)]:
            self._items.pop(key, None)
            self._changed.pop(key, None)
