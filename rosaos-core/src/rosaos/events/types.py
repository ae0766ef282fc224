"""The kernel's events and their payloads: what enters the queue, typed.

Every input to the kernel (user speech, typed chat, a process's callback, a device notice, an
error, a fired timer) is an :class:`Event` whose payload is one of these models. They live in
this low layer so that every part of rosaOS (the offline engine in ``models/`` and ``intents/``,
the processes, the kernel, the API) reads the same typed objects; only an LLM reads them as text
(:mod:`rosaos.kernel.event_text`). The store is :mod:`rosaos.kernel.event_store`.
"""

from __future__ import annotations

from datetime import datetime
from typing import Annotated, Any, Literal, NamedTuple

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, field_validator

from rosaos.events.callback import WorkerCallback

EventKind = Literal["user_said", "user_typed", "worker_callback", "device_notice", "error", "timer_fired"]

SOURCE_PATTERN = r"^[A-Za-z0-9_.:@/-]+$"
IdempotencyKey = Annotated[str, Field(min_length=1, max_length=200)]
Source = Annotated[str, Field(min_length=1, max_length=100, pattern=SOURCE_PATTERN)]


NOT_BLANK = r"[^\s\x1c-\x1f\x85]"
"""A character that is whitespace to no one: not to JSON Schema's regex (ECMAScript), pydantic's
(Rust) or Python's ``str.strip``, which also strips U+001C-U+001F and U+0085. A published
``minLength: 1`` alone let "\u0085" through the schema and then failed once stripped (CI,
2026-11-26, schemathesis)."""


class UserText(BaseModel):
    """What the user said or typed: one sentence or a few, never blank."""

    model_config = ConfigDict(extra="forbid", str_strip_whitespace=True)

    text: str = Field(min_length=1, max_length=4000, pattern=NOT_BLANK)


class DeviceNotice(BaseModel):
    """Something a device reports on its own: a bump, a low battery, a button press."""

    model_config = ConfigDict(extra="forbid")

    device: str = Field(min_length=1, max_length=100)
    message: str = Field(min_length=1, max_length=4000)
    data: dict[str, Any] = Field(default_factory=dict)
    """Any JSON, nested at most :data:`MAX_DATA_DEPTH` levels (deeper breaks JSON encoders)."""
    name: str | None = Field(default=None, pattern=r"^[a-z][a-z0-9_]{0,63}$")
    """What happened, as the driver declares it (``battery_low``, ``person_seen``); see
    :mod:`rosaos.notices.notice_board`. None for a free-form notice posted by hand."""
    driver: str | None = Field(default=None, max_length=100)
    importance: Literal["info", "notify"] = "info"
    """``notify``: the kernel tells the user; ``info``: it notes it and stays quiet."""

    @field_validator("data")
    @classmethod
    def _not_too_deep(cls, data: dict[str, Any]) -> dict[str, Any]:
        if _depth(data) > MAX_DATA_DEPTH:
            raise ValueError(f"nested more than {MAX_DATA_DEPTH} levels deep; flatten it")
        return data


MAX_DATA_DEPTH = 32


def _depth(value: Any, level: int = 1) -> int:
    """How deep ``value`` nests; stops counting past the limit, so a hostile body costs little."""
    if level > MAX_DATA_DEPTH:
        return level
    children = value.values() if isinstance(value, dict) else value if isinstance(value, list) else ()
    return max((_depth(child, level + 1) for child in children), default=level)


class ErrorReport(BaseModel):
    """A failure the kernel should know about; ``source_event`` is the event that caused it."""

    model_config = ConfigDict(extra="forbid")

    message: str = Field(min_length=1, max_length=4000)
    source_event: int | None = Field(default=None, ge=1)


class TimerFired(BaseModel):
    """A timer fell due (see :mod:`rosaos.timers.timer_book`): the kernel does its action now."""

    model_config = ConfigDict(extra="forbid")

    timer_id: int = Field(ge=1, le=2**53 - 1)  # exact as a JSON number (see kernel/api/routes.py MAX_ID)
    action: str = Field(min_length=1, max_length=4000)
    due: datetime
    late_seconds: float = Field(default=0.0, ge=0)
    """How long after ``due`` it fired: more than a few seconds means the kernel was down."""

    @property
    def late(self) -> bool:
        """Whether it fired late enough to say so (the kernel was down, or busy starting)."""
        return self.late_seconds >= LATE_AFTER_SECONDS


LATE_AFTER_SECONDS = 5.0
"""A timer that fires later than this after it was due is reported as late."""

EventPayload = UserText | WorkerCallback | DeviceNotice | ErrorReport | TimerFired


class _NewEventBase(BaseModel):
    model_config = ConfigDict(extra="forbid")

    source: Source = "api"
    """Who sent it: ``web``, ``cli``, ``voice``, ``worker``, a device name."""
    idempotency_key: IdempotencyKey | None = None
    """Send the same key again (a retry) and the first event's id comes back; nothing is enqueued."""


class UserSaidEvent(_NewEventBase):
    """The voice front end heard the user (after the wake word)."""

    kind: Literal["user_said"]
    payload: UserText


class UserTypedEvent(_NewEventBase):
    """The user typed in the web page or the CLI chat."""

    kind: Literal["user_typed"]
    payload: UserText


class WorkerCallbackEvent(_NewEventBase):
    """A process ended; its worker reports the outcome."""

    kind: Literal["worker_callback"]
    payload: WorkerCallback


class DeviceNoticeEvent(_NewEventBase):
    """A device reported something on its own."""

    kind: Literal["device_notice"]
    payload: DeviceNotice


class ErrorEvent(_NewEventBase):
    """An error the kernel should see and may act on."""

    kind: Literal["error"]
    payload: ErrorReport


class TimerFiredEvent(_NewEventBase):
    """A timer fell due; the kernel's timer clock queues it, once per timer."""

    kind: Literal["timer_fired"]
    payload: TimerFired


NewEvent = Annotated[
    UserSaidEvent | UserTypedEvent | WorkerCallbackEvent | DeviceNoticeEvent | ErrorEvent | TimerFiredEvent,
    Field(discriminator="kind"),
]
"""Any event the queue takes, told apart by ``kind`` (``POST /event`` takes :data:`ExternalEvent`)."""

NEW_EVENT: TypeAdapter[NewEvent] = TypeAdapter(NewEvent)

ExternalEvent = Annotated[
    UserSaidEvent | UserTypedEvent | DeviceNoticeEvent | ErrorEvent,
    Field(discriminator="kind"),
]
"""What ``POST /event`` takes: the kinds that come from outside the kernel. A process's end and a
timer's firing are queued only by the kernel itself (its pool's pipe, its timer table)."""


class Event(BaseModel):
    """An event as stored: what was sent, when, and whether the kernel has handled it."""

    id: int
    time: datetime
    kind: EventKind
    source: str
    payload: EventPayload
    idempotency_key: str | None = None
    handled: bool = False
    attempts: int = 0
    """How many times :meth:`EventStore.next_pending` has returned it. Above 1 means it is being
    redelivered after a crash; the kernel may give up on an event that keeps failing."""


class Appended(NamedTuple):
    """The outcome of :meth:`EventStore.append`."""

    id: int
    duplicate: bool
    """True when the idempotency key was seen before: ``id`` is the first event's, nothing was enqueued."""
    conflict: bool = False
    """A duplicate whose kind or payload differs from the first event's: the key was reused for
    something else (the API answers 409, as the IETF Idempotency-Key draft does)."""
