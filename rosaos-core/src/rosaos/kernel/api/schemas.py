"""What the kernel's HTTP API speaks: what it needs from the kernel, and its bodies and answers.

:class:`KernelRuntime` is the API's side of the running kernel (``rosaos up`` implements it); the
pydantic models are the request bodies and answers of the routes in :mod:`rosaos.kernel.api.routes`,
and their names are the schema names in the OpenAPI document.
"""

from __future__ import annotations

from collections.abc import Sequence
from datetime import datetime
from typing import Any, Literal, Protocol

from pydantic import BaseModel, ConfigDict, Field, model_validator

from rosaos.config import MapOrigin
from rosaos.confirmations.confirmation_desk import ConfirmationDesk
from rosaos.events.plan import Plan
from rosaos.events.types import NOT_BLANK, IdempotencyKey, Source
from rosaos.kernel.activity import ActivityLog
from rosaos.kernel.api.login_codes import LoginCodes
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.intake import Intake
from rosaos.kernel.updates import Update, UpdateStream
from rosaos.memory.sightings import SightingLog
from rosaos.memory.store import MemoryStore
from rosaos.processes.manager import ProcessInfo
from rosaos.timers.timer_book import TimerBook


class KernelRuntime(Protocol):
    """What the HTTP API needs from the running kernel. ``rosaos up`` implements it."""

    @property
    def events(self) -> EventStore:
        """The durable event queue."""

    @property
    def intake(self) -> Intake:
        """The one way into the event queue: append, publish, side effects."""

    @property
    def updates(self) -> UpdateStream:
        """The updates stream (same SQLite file)."""

    @property
    def confirmations(self) -> ConfirmationDesk:
        """The pending confirmation questions."""

    @property
    def activity(self) -> ActivityLog:
        """The activity log: every tool call of every process (same SQLite file)."""

    @property
    def timers(self) -> TimerBook:
        """The durable timers (same SQLite file)."""

    @property
    def memory(self) -> MemoryStore:
        """Named places and what people said (``memory.db``)."""

    @property
    def sightings(self) -> SightingLog:
        """What the robots saw (``memory.db``)."""

    @property
    def login_codes(self) -> LoginCodes:
        """Login codes; ``rosaos up`` mints the first one and prints its link."""

    @property
    def token(self) -> str:
        """The bearer token every protected route requires."""

    @property
    def model_description(self) -> str:
        """``offline default``, or the model's name (``openai:gpt-5.2``); nothing secret."""

    @property
    def model_notice(self) -> str | None:
        """Shown as a banner when no model is configured: how to set one. None otherwise."""

    async def processes(self, include_ended: bool = False) -> Sequence[ProcessInfo]:
        """The processes to show, running ones only unless ``include_ended``."""

    async def terminate(self, process_id: int) -> ProcessInfo:
        """Terminate a process and return it; raise ``KeyError`` for an unknown id."""

    async def launch(self, task: str, devices: list[str], plan: Plan | None = None) -> ProcessInfo:
        """Launch a process outside the kernel agent (a card control); raise ``LaunchRefused``."""

    async def devices(self) -> Sequence[DeviceView]:
        """Every device with its status, live state and the processes holding it."""

    async def emergency_stop(self, reason: str) -> EmergencyStopReport:
        """Terminate every process, call every device's ``safe_stop``, latch until reset."""

    async def reset_emergency_stop(self) -> EmergencyStopState:
        """Unlatch the emergency stop."""

    def emergency_stop_state(self) -> EmergencyStopState:
        """Whether the emergency stop is latched, why and since when; survives a restart."""

    async def understand(self, text: str) -> Understanding:
        """Whether the offline engine can act on ``text`` as it stands; launches nothing."""

    def readiness(self) -> Readiness:
        """Which devices are still starting and whether the worker pool is warm."""


# --- bodies and answers ----------------------------------------------------------------------------


class SayRequest(BaseModel):
    """``POST /chat`` and ``POST /stt``: one thing the user typed or said."""

    model_config = ConfigDict(extra="forbid", str_strip_whitespace=True)

    text: str = Field(
        min_length=1, max_length=4000, pattern=NOT_BLANK, description="Stripped; must not be blank."
    )
    idempotency_key: IdempotencyKey | None = None
    source: Source | None = Field(default=None, description="Defaults to 'chat' or 'stt'.")


class UnderstandRequest(BaseModel):
    """``POST /understand``: a sentence to judge, e.g. the voice front end's draft transcript."""

    model_config = ConfigDict(extra="forbid", str_strip_whitespace=True)

    text: str = Field(
        min_length=1, max_length=4000, pattern=NOT_BLANK, description="Stripped; must not be blank."
    )


class Understanding(BaseModel):
    """What the offline engine makes of a sentence, without acting on it.

    ``complete`` is true when the sentence is a whole command the engine would run as it stands
    ("turn on the kitchen light"); false for a beginning ("turn on the"), a question back, or
    nothing understood. The voice front end ends a turn early only on ``complete``.
    """

    text: str
    complete: bool
    kind: str = Field(description="The engine's verdict: plans, clarify, no_match, or no_engine.")
    moves: bool = Field(
        default=False,
        description="A whole command that would set a robot moving: the voice front end waits the "
        "full pause before ending such a turn ('drive forward ... one meter').",
    )


class Accepted(BaseModel):
    """The event is committed: it will be handled even if the kernel restarts."""

    id: int
    duplicate: bool = Field(description="True when the idempotency key was seen: id is the first event's.")


class ProgressView(BaseModel):
    """What a running process's device tool last reported: ``progress`` of ``total`` (if given)."""

    model_config = ConfigDict(from_attributes=True)

    device: str
    progress: float
    total: float | None = None
    message: str = ""
    at: datetime


class ProcessView(BaseModel):
    """One process agent and the devices it holds (its leases)."""

    model_config = ConfigDict(from_attributes=True, extra="allow")

    id: int
    task: str
    devices: list[str]
    state: str
    started_at: datetime | None = None
    ended_at: datetime | None = None
    worker_pid: int | None = None
    progress: ProgressView | None = None
    """The latest progress of a long task (a robot's search), while it runs."""
    summary: str = ""
    """The task in words (filled from ``task``: the plan and the follow-up are fields of their own)."""
    then: str | None = None
    """What the kernel does when this process succeeds ("turn the lamp green"), if anything."""

    @model_validator(mode="after")
    def _words(self) -> ProcessView:
        self.summary = self.summary or self.task.strip()
        return self


class DeviceView(BaseModel):
    """One device instance with its live state as its ``get_state`` tool returns it."""

    model_config = ConfigDict(from_attributes=True)

    name: str
    driver: str
    concurrency: str
    backend: str | None = None
    status: str
    url: str | None = None
    state: dict[str, Any] | None = None
    description: str = ""
    card: dict[str, Any] | None = None
    """How the web page draws the state (``rosaos.cards``): ``{"widgets": [...]}``; null for a key list."""
    held_by: list[int] = Field(default_factory=list)
    """Ids of the running processes that hold this device (their leases)."""
    map_origin: MapOrigin | None = None
    """A robot's pose in the shared floor map (``[devices.NAME] map_origin``); null: at the map's origin."""


class EmergencyStopState(BaseModel):
    """``GET /estop``: whether the emergency stop is latched, why, and since when."""

    latched: bool
    reason: str | None = None
    time: datetime | None = None
    """When it was (last) pressed; None when not latched."""
    untold_hosts: list[str] = Field(default_factory=list)
    """Devices whose host could not be told the latch (or its reset) yet: it is pushed again every
    few seconds, but until then such a host would still run a tool call that reaches it."""


class DeviceSafeStop(BaseModel):
    """What one device's ``safe_stop`` did during an emergency stop."""

    name: str
    ok: bool
    detail: str


class EmergencyStopReport(EmergencyStopState):
    """``POST /estop``: the latch, the processes terminated and each device's ``safe_stop``."""

    terminated: list[int] = Field(default_factory=list)
    devices: list[DeviceSafeStop] = Field(default_factory=list)
    saved: bool = True
    """False when the latch could not be written to the event store: a restart would forget it."""


class Readiness(BaseModel):
    """What ``rosaos up`` still starts after its banner (the banner comes before devices and pool)."""

    ready: bool = Field(
        description="Every device has had its first start and the worker pool is warm: a command "
        "sent now waits for nothing but its own work. `rosaos ready` waits for this."
    )
    pool: Literal["warming", "warm", "failed"] = Field(
        description="The warm worker pool; 'failed': no process can run (the console says why)."
    )
    devices_starting: int = Field(description="Devices that have not had their first start yet.")
    starting: list[str] | None = Field(
        default=None,
        description="Their names, only for a request with the bearer token (names are not public).",
    )


class Health(Readiness):
    """Open to anyone who can reach the port, so nothing secret (device names need the token)."""

    status: Literal["ok"] = "ok"
    version: str
    model: str
    model_notice: str | None
    uptime_seconds: float
    pending_events: int


class UpdatesPage(BaseModel):
    """``GET /updates`` without ``Accept: text/event-stream``: poll with ``after=last_id``."""

    updates: list[Update]
    last_id: int = Field(description="Pass as ?after= next time; unchanged when there is nothing new.")


class LoginRequest(BaseModel):
    model_config = ConfigDict(extra="forbid")

    code: str = Field(min_length=1, max_length=200)


class LoginToken(BaseModel):
    token: str
    token_type: Literal["bearer"] = "bearer"


class LoginLink(BaseModel):
    code: str
    url: str = Field(description="Open it in a browser: http://host:port/#login=<code>.")
    expires_in: float = Field(description="Seconds until the code stops working. It works once.")


class EmergencyStopRequest(BaseModel):
    model_config = ConfigDict(extra="forbid")

    reason: str = Field(default="requested by a person", min_length=1, max_length=500)


class ErrorBody(BaseModel):
    """Every error the API answers: what was wrong and how to fix it."""

    detail: str


class Problem(BaseModel):
    """One invalid part of a request."""

    loc: list[str]
    msg: str
    type: str


class InvalidRequest(BaseModel):
    """A 422: the request's parts that did not validate, as one sentence and one by one."""

    detail: str
    errors: list[Problem] = Field(default_factory=list)


def _error(description: str) -> dict[str, Any]:
    return {"model": ErrorBody, "description": description}


COMMON_ERRORS: dict[int | str, dict[str, Any]] = {
    403: _error("A browser request from a foreign origin"),
    413: _error("The body is larger than the API accepts"),
    421: _error("A Host name that is neither loopback nor allowed (DNS-rebinding protection)"),
    422: {"model": InvalidRequest, "description": "The request did not validate"},
}
"""Answers any route may give; every error body has ``detail``."""
PROTECTED_ERRORS: dict[int | str, dict[str, Any]] = {
    **COMMON_ERRORS,
    400: _error("A header or parameter that cannot be used"),
    401: _error("Missing or wrong bearer token"),
    404: _error("No such event, process or device"),
    409: _error("An Idempotency-Key reused with a different body, or a conflicting request"),
}
"""Answers of the routes behind the token."""
