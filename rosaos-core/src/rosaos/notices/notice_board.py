"""Device notices, driver side: what a driver declares and posts, and the board that holds them.

A driver declares its notices in :attr:`rosaos.drivers.DriverSpec.notices` and posts one with
:meth:`rosaos.drivers.DeviceContext.notify` from its backend or server::

    ctx.notify("battery_low", {"battery": 0.12}, message="battery at 12 %")

The notice lands on the instance's :class:`NoticeBoard` (one per instance, so it does not matter
whether an instance has a process of its own or shares one with others). The hosting layer serves
the board at ``GET /notices`` next to ``/mcp``, behind the device's bearer token, and the kernel
long-polls it (:mod:`rosaos.notices.notice_watcher`), turning each notice into a ``[Device notice]`` event.
The kernel pulls, so a device never needs the kernel's address or its token, and a device served
by ``rosaos serve-device`` on a robot's own computer works the same way.
"""

from __future__ import annotations

import asyncio
import re
import secrets
import threading
from collections import deque
from collections.abc import Awaitable, Callable, Mapping
from datetime import UTC, datetime
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator
from starlette.requests import Request
from starlette.responses import JSONResponse, Response

NoticeImportance = Literal["info", "notify"]
"""``notify``: the user should hear about it (the kernel tells them through the Reachy Mini).
``info``: worth knowing (the kernel and the web page see it), not worth interrupting anyone for."""

NOTICE_NAME = re.compile(r"^[a-z][a-z0-9_]{0,63}$")
BOARD_SIZE = 100
"""Notices a board keeps for the kernel to read; older ones are dropped first."""
MAX_WAIT = 30.0
"""Longest long-poll a ``GET /notices`` may ask for, in seconds."""


class NoticeError(ValueError):
    """A notice that breaks its declaration: unknown name, or data that does not validate."""


class NoticeSpec(BaseModel):
    """One notice a driver may post, as declared in ``DriverSpec.notices``."""

    model_config = ConfigDict(arbitrary_types_allowed=True, frozen=True, extra="forbid")

    description: str = Field(min_length=1)
    """When the driver posts it, in one sentence (documentation and the conformance kit)."""
    importance: NoticeImportance = "info"
    """Default importance; a post may raise or lower it (a battery at 30 % vs 10 %)."""
    data: type[BaseModel] | None = None
    """The pydantic model its ``data`` must validate against; None means "no data"."""
    example: dict[str, Any] = Field(default_factory=dict)
    """A valid ``data`` value; the conformance kit checks that it validates."""

    def validate_data(self, data: Mapping[str, Any]) -> dict[str, Any]:
        """``data`` checked against :attr:`data` and dumped to JSON-ready values; NoticeError if not."""
        if self.data is None:
            if data:
                raise NoticeError(f"declares no data, got {sorted(data)}")
            return {}
        try:
            return self.data.model_validate(dict(data)).model_dump(mode="json")
        except ValidationError as error:
            raise NoticeError(str(error)) from None


class Notice(BaseModel):
    """One posted notice, as ``GET /notices`` returns it and the kernel enqueues it."""

    model_config = ConfigDict(extra="forbid")

    seq: int = Field(ge=1)
    """Position on the board, from 1, per board life (see :attr:`NoticeBatch.board`)."""
    name: str = Field(pattern=NOTICE_NAME.pattern)
    device: str = Field(min_length=1, max_length=100)
    """The instance name (``turtlebot``)."""
    driver: str = Field(min_length=1, max_length=100)
    importance: NoticeImportance
    message: str = Field(min_length=1, max_length=1000)
    """One sentence a person can read or hear ("turtlebot: battery at 12 %")."""
    data: dict[str, Any] = Field(default_factory=dict)
    time: datetime


class NoticeBatch(BaseModel):
    """The body of ``GET /notices``: notices after the cursor, and where to continue."""

    board: str
    """Identifies this board's life: a restarted device has a new one and numbers from 1 again."""
    next: int
    """Pass as ``after`` next time."""
    notices: list[Notice]


class NoticeBoard:
    """The notices of one device instance, kept for the kernel to read.

    :meth:`post` may be called from the event loop or from any thread (an SDK callback).
    """

    def __init__(
        self, instance: str = "device", driver: str = "device", specs: Mapping[str, NoticeSpec] | None = None
    ) -> None:
        self.instance = instance
        self.driver = driver
        self.specs = dict(specs) if specs is not None else None
        """Declared notices; None (a context built by hand in a test) accepts any valid name."""
        self.board = secrets.token_hex(6)
        self._notices: deque[Notice] = deque(maxlen=BOARD_SIZE)
        self._seq = 0
        self._lock = threading.Lock()
        self._waiters: list[tuple[asyncio.AbstractEventLoop, asyncio.Event]] = []
        self._closed = False

    def post(
        self,
        name: str,
        data: Mapping[str, Any] | None = None,
        *,
        message: str | None = None,
        importance: NoticeImportance | None = None,
    ) -> Notice:
        """Post a notice; returns it. Raises :class:`NoticeError` if it breaks its declaration."""
        if not NOTICE_NAME.match(name):
            raise NoticeError(f"notice name {name!r} must match {NOTICE_NAME.pattern}")
        spec = None
        if self.specs is not None:
            spec = self.specs.get(name)
            if spec is None:
                declared = ", ".join(sorted(self.specs)) or "none"
                raise NoticeError(
                    f"{self.driver} does not declare a notice {name!r} (declared: {declared}); "
                    "add it to DriverSpec.notices"
                )
        clean = spec.validate_data(data or {}) if spec is not None else dict(data or {})
        text = message or f"{self.instance}: {name.replace('_', ' ')}"
        with self._lock:
            self._seq += 1
            notice = Notice(
                seq=self._seq,
                name=name,
                device=self.instance,
                driver=self.driver,
                importance=importance or (spec.importance if spec is not None else "info"),
                message=text[:1000],
                data=clean,
                time=datetime.now(UTC),
            )
            self._notices.append(notice)
            waiters, self._waiters = self._waiters, []
        for loop, event in waiters:
            if not loop.is_closed():
                loop.call_soon_threadsafe(event.set)
        return notice

    def release_waiters(self) -> None:
        """End every long poll now and answer later ones at once: the server is stopping, and
        uvicorn would otherwise wait for those requests before it can shut down."""
        with self._lock:
            self._closed = True
            waiters, self._waiters = self._waiters, []
        for loop, event in waiters:
            if not loop.is_closed():
                loop.call_soon_threadsafe(event.set)

    def after(self, seq: int, board: str | None = None) -> NoticeBatch:
        """The notices after ``seq``; all kept ones when ``board`` names an earlier life."""
        start = 0 if board is not None and board != self.board else seq
        with self._lock:
            notices = [notice for notice in self._notices if notice.seq > start]
            return NoticeBatch(board=self.board, next=self._seq, notices=notices)

    @property
    def closed(self) -> bool:
        """The server is stopping: long polls are answered at once."""
        return self._closed

    def watch(self, event: asyncio.Event) -> None:
        """Set ``event`` (once) at the next post or when the board closes."""
        with self._lock:
            self._waiters.append((asyncio.get_running_loop(), event))

    def unwatch(self, event: asyncio.Event) -> None:
        with self._lock:
            self._waiters = [w for w in self._waiters if w[1] is not event]

    async def wait_after(self, seq: int, board: str | None = None, wait: float = 0.0) -> NoticeBatch:
        """Like :meth:`after`, but waits up to ``wait`` seconds for one to arrive (long poll)."""
        batch = self.after(seq, board)
        if batch.notices or wait <= 0 or self._closed:
            return batch
        event = asyncio.Event()
        self.watch(event)
        try:
            async with asyncio.timeout(min(wait, MAX_WAIT)):
                await event.wait()
        except TimeoutError:
            pass
        finally:
            self.unwatch(event)
        return self.after(seq, board)


def check_notice_specs(specs: Mapping[str, NoticeSpec]) -> list[str]:
    """What is wrong with a driver's declared notices (empty when they validate)."""
    problems = []
    for name, spec in specs.items():
        if not NOTICE_NAME.match(name):
            problems.append(f"notice name {name!r} must match {NOTICE_NAME.pattern}")
        try:
            spec.validate_data(spec.example)
        except NoticeError as error:
            problems.append(f"notice {name!r}: its example does not validate: {error}")
        if spec.data is not None:
            try:
                spec.data.model_json_schema()
            except Exception as error:  # pydantic raises several kinds for unschemable types
                problems.append(f"notice {name!r}: data has no JSON schema: {error}")
    return problems


class _NoticeQuery(BaseModel):
    after: int = Field(default=0, ge=0)
    board: str | None = Field(default=None, max_length=64)
    wait: float = Field(default=0.0, ge=0.0, le=MAX_WAIT)

    @field_validator("board")
    @classmethod
    def _hex(cls, value: str | None) -> str | None:
        if value is not None and not re.fullmatch(r"[0-9a-f]*", value):
            raise ValueError("board is the hex id a previous answer gave")
        return value or None


def notice_endpoint(board: NoticeBoard) -> Callable[[Request], Awaitable[Response]]:
    """The Starlette endpoint for ``GET /notices?after=N&board=ID&wait=S`` on ``board``."""

    async def notices(request: Request) -> Response:
        try:
            query = _NoticeQuery.model_validate(dict(request.query_params))
        except ValidationError as error:
            return JSONResponse({"detail": error.errors(include_url=False, include_context=False)}, 422)
        batch = await board.wait_after(query.after, query.board, query.wait)
        return JSONResponse(batch.model_dump(mode="json"))

    return notices
