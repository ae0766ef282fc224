"""The emergency-stop latch, held by the device host too: a latched host refuses every tool that acts.

The kernel's latch refuses new processes, but a tool call that reaches a device another way (a
worker that outlived its kill, a person with the token) would still run. So the kernel pushes the
latch to every device host (``POST /latch``, behind the token), and a latched host refuses every
tool that is not read-only — except the stops — until the kernel tells it the latch was reset.
``GET /latch`` says whether the host is latched.

A host starts latched from its first moment when the latch is set: the latch is kept in
:data:`LATCH_FILE` in the data directory. The kernel writes it before it tells any host
(:mod:`rosaos.kernel.host_latch`), so a host the kernel starts (sharing its data directory) reads
it at start; every host writes its own copy when told, so a remote ``serve-device`` host that
restarts while latched starts latched too. Without the file it starts unlatched and is told within
seconds by the kernel's periodic push. A file that cannot be read starts the host latched: only
the kernel's reset, a person's decision, unlatches it.
"""

from __future__ import annotations

import logging
from collections.abc import Awaitable, Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from fastmcp.server.middleware import CallNext, Middleware, MiddlewareContext
from pydantic import BaseModel, Field, ValidationError
from starlette.requests import Request
from starlette.responses import JSONResponse

from rosaos.devices.deadman import NOT_ARMING, ReadOnlyTools
from rosaos.devices.run_files import write_atomic

log = logging.getLogger("rosaos.devices.latch")

LATCH_PATH = "/latch"
LATCH_FILE = "host-latch.json"
"""The latch as last set, in the data directory (:class:`LatchState` as JSON)."""


class LatchState(BaseModel):
    """Whether a host is latched, and why (the kernel's reason)."""

    latched: bool
    reason: str = Field(default="", max_length=500)
    since: datetime | None = None


class HostLatch:
    """One host's copy of the kernel's emergency-stop latch, kept in ``data_dir`` when given."""

    def __init__(self, instance: str, data_dir: Path | None = None) -> None:
        self.instance = instance
        self.file = data_dir / LATCH_FILE if data_dir is not None else None
        self.state = read_latch(self.file) if self.file is not None else LatchState(latched=False)
        if self.state.latched:
            log.warning("%s: starting latched: %s", instance, self.state.reason)

    def set(self, latched: bool, reason: str) -> LatchState:
        if latched and not self.state.latched:
            log.warning("%s: emergency stop latched at this host: %s", self.instance, reason)
        if not latched and self.state.latched:
            log.warning("%s: emergency stop reset at this host", self.instance)
        since = (self.state.since if self.state.latched else None) or datetime.now(UTC)
        self.state = LatchState(latched=latched, reason=reason, since=since if latched else None)
        if self.file is not None:
            write_latch(self.file, self.state)
        return self.state


def read_latch(path: Path) -> LatchState:
    """The latch kept in ``path``: unlatched when there is none, latched when it cannot be read."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return LatchState(latched=False)
    except OSError as error:
        return LatchState(latched=True, reason=f"the kept latch {path} could not be read ({error})")
    try:
        return LatchState.model_validate_json(text)
    except ValidationError:
        return LatchState(latched=True, reason=f"the kept latch {path} could not be read ({text[:100]!r})")


def write_latch(path: Path, state: LatchState) -> None:
    """Keep ``state`` in ``path`` for the next start; a failure is logged (the latch in memory holds)."""
    try:
        write_atomic(path, state.model_dump_json())
    except OSError:
        log.exception("could not keep the latch in %s: a restart would start unlatched", path)


class LatchMiddleware(Middleware):
    """Refuses every call of a tool that acts while the host is latched."""

    def __init__(self, latch: HostLatch, read_only: ReadOnlyTools) -> None:
        self.latch = latch
        self.read_only = read_only

    async def on_call_tool(self, context: MiddlewareContext[Any], call_next: CallNext[Any, Any]) -> Any:
        name = getattr(context.message, "name", "")
        if self.latch.state.latched and name not in NOT_ARMING and not await self.read_only(name):
            raise ToolError(
                f"{self.latch.instance}: the emergency stop is latched ({self.latch.state.reason}); this "
                f"host refuses {name} and every tool that acts until a person resets it "
                "(`rosaos estop --reset` or the web page); reading state still works"
            )
        return await call_next(context)


def latch_endpoint(latch: HostLatch) -> Callable[[Request], Awaitable[JSONResponse]]:
    """``GET /latch``: the state; ``POST /latch`` ``{"latched": bool, "reason": str}``: set it."""

    async def endpoint(request: Request) -> JSONResponse:
        if request.method == "POST":
            try:
                wanted = LatchState.model_validate_json(await request.body())
            except ValidationError as error:
                return JSONResponse(
                    {"error": f'send {{"latched": true|false, "reason": "..."}}: {error.errors()[0]["msg"]}'},
                    status_code=422,
                )
            latch.set(wanted.latched, wanted.reason)
        return JSONResponse(latch.state.model_dump(mode="json"))

    return endpoint


def add_latch(server: FastMCP, instance: str, data_dir: Path | None = None) -> HostLatch:
    """Give ``server`` the latch: the middleware and ``/latch`` (kept in ``data_dir`` when given)."""
    latch = HostLatch(instance, data_dir)
    server.add_middleware(LatchMiddleware(latch, ReadOnlyTools(server)))
    server.custom_route(LATCH_PATH, methods=["GET", "POST"])(latch_endpoint(latch))
    return latch
