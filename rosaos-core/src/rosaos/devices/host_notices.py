"""Every notice board a host process serves, read with one long poll: ``POST /host/notices``.

The shared host serves hundreds of simulated instances, each on its own port with its own board
(:mod:`rosaos.notices.notice_board`). Polling each board on its own kept one open request per device:
at 300 lamps the kernel spent most of its idle CPU (about 8 % of a core) renewing them. So every
device server in a process also answers ``POST /host/notices``, which reads any of the process's
boards at once: the kernel sends each board's cursor, and the answer waits until one of them has
something new (or ``wait`` runs out). One request per host, whatever the number of devices.

It is served behind the same bearer token as the device's ``/mcp``, and answers only for boards
served with that same token: a caller learns nothing about a device it could not reach anyway.
A board the process does not serve is listed in :attr:`HostNoticeAnswer.unknown`, so a kernel
that guessed a host's members wrongly (a shared host split in halves) polls those on their own.
"""

from __future__ import annotations

import asyncio
import hmac
import re

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator
from starlette.requests import Request
from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Receive, Scope, Send

from rosaos.notices.notice_board import MAX_WAIT, NoticeBatch, NoticeBoard

HOST_NOTICES_PATH = "/host/notices"
MAX_BOARDS = 10_000
"""Most boards one query may name (a bound on a request's work, far above any real host)."""


class BoardCursor(BaseModel):
    """Where the caller is on one board: as :class:`NoticeBatch` last told it."""

    model_config = ConfigDict(extra="forbid")

    after: int = Field(default=0, ge=0)
    board: str | None = Field(default=None, max_length=64)

    @field_validator("board")
    @classmethod
    def _hex(cls, value: str | None) -> str | None:
        if value is not None and not re.fullmatch(r"[0-9a-f]*", value):
            raise ValueError("board is the hex id a previous answer gave")
        return value or None


class HostNoticeQuery(BaseModel):
    """The body of ``POST /host/notices``: a cursor per instance, and how long to wait."""

    model_config = ConfigDict(extra="forbid")

    boards: dict[str, BoardCursor] = Field(max_length=MAX_BOARDS)
    wait: float = Field(default=0.0, ge=0.0, le=MAX_WAIT)


class HostNoticeAnswer(BaseModel):
    """The answer: only the boards with something new (notices, or a new board life)."""

    batches: dict[str, NoticeBatch] = Field(default_factory=dict)
    unknown: list[str] = Field(default_factory=list)
    """Instances this process does not serve (with this token): poll them on their own."""


class HostBoards:
    """The boards served in this process, by instance name, each with the token it is served with."""

    def __init__(self) -> None:
        self._boards: dict[str, tuple[NoticeBoard, str]] = {}

    def add(self, board: NoticeBoard, token: str) -> None:
        self._boards[board.instance] = (board, token)

    def __contains__(self, instance: object) -> bool:
        return instance in self._boards

    def remove(self, board: NoticeBoard) -> None:
        entry = self._boards.get(board.instance)
        if entry is not None and entry[0] is board:
            del self._boards[board.instance]

    async def wait_many(self, query: HostNoticeQuery, token: str) -> HostNoticeAnswer:
        """What is new on the named boards; waits up to ``query.wait`` seconds for something."""
        known: dict[str, NoticeBoard] = {}
        unknown: list[str] = []
        for name in query.boards:
            entry = self._boards.get(name)
            if entry is not None and hmac.compare_digest(entry[1].encode(), token.encode()):
                known[name] = entry[0]
            else:
                unknown.append(name)
        answer = _collect(query, known, unknown)
        if answer.batches or query.wait <= 0 or not known or any(b.closed for b in known.values()):
            return answer
        event = asyncio.Event()
        for board in known.values():
            board.watch(event)
        try:
            async with asyncio.timeout(query.wait):
                await event.wait()
        except TimeoutError:
            pass
        finally:
            for board in known.values():
                board.unwatch(event)
        return _collect(query, known, unknown)


def _collect(query: HostNoticeQuery, known: dict[str, NoticeBoard], unknown: list[str]) -> HostNoticeAnswer:
    batches = {}
    for name, board in known.items():
        cursor = query.boards[name]
        batch = board.after(cursor.after, cursor.board)
        if batch.notices or batch.board != cursor.board or batch.next != cursor.after:
            batches[name] = batch
    return HostNoticeAnswer(batches=batches, unknown=unknown)


HOST_BOARDS = HostBoards()
"""This process's boards; :func:`rosaos.devices.serve.serve_http` adds and removes them."""


def with_host_notices(app: ASGIApp, token: str, boards: HostBoards = HOST_BOARDS) -> ASGIApp:
    """``app`` that also answers ``POST /host/notices`` (put it behind the token check)."""

    async def wrapped(scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope.get("path") != HOST_NOTICES_PATH:
            await app(scope, receive, send)
            return
        request = Request(scope, receive)
        if request.method != "POST":
            response = JSONResponse({"detail": f"use POST on {HOST_NOTICES_PATH}"}, 405)
        else:
            try:
                query = HostNoticeQuery.model_validate_json(await request.body())
            except ValidationError as error:
                details = error.errors(include_url=False, include_context=False, include_input=False)
                response = JSONResponse({"detail": details}, 422)
            else:
                answer = await boards.wait_many(query, token)
                response = JSONResponse(answer.model_dump(mode="json"))
        await response(scope, receive, send)

    return wrapped
