"""The emergency-stop latch, held by the device host too: a latched host refuses every tool that acts.

The kernel's latch refuses new processes, but a tool call that reaches a device another way (a
worker that outlived its kill, a person with the token) would still run. So the kernel pushes the
latch to every device host (``POST /latch``, behind the token), and a latched host refuses every
tool that is not read-only — except the stops — until the kernel tells it the latch was reset.
``GET /latch`` says whether the host is latched.
"""

from __future__ import annotations

import logging
from collections.abc import Awaitable, Callable
from datetime import UTC, datetime
from typing import Any

from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from fastmcp.server.middleware import CallNext, Middleware, MiddlewareContext
from pydantic import BaseModel, Field, ValidationError
from starlette.requests import Request
from starlette.responses import JSONResponse

from rosaos.devices.deadman import NOT_ARMING, ReadOnlyTools

log = logging.getLogger("rosaos.devices.latch")

LATCH_PATH = "/latch"


class LatchState(BaseModel):
    """Whether a host is latched, and why (the kernel's reason)."""

    latched: bool
    reason: str = Field(default="", max_length=500)
    since: datetime | None = None


class HostLatch:
    """One host's copy of the kernel's emergency-stop latch."""

    def __init__(self, instance: str) -> None:
        self.instance = instance
        self.state = LatchState(latched=False)

    def set(self, latched: bool, reason: str) -> LatchState:
        if latched and not self.state.latched:
            log.warning("%s: emergency stop latched at this host: %s", self.instance, reason)
        if not latched and self.state.latched:
            log.warning("%s: emergency stop reset at this host", self.instance)
        self.state = LatchState(latched=latched, reason=reason, since=datetime.now(UTC) if latched else None)
        return self.state


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


def add_latch(server: FastMCP, instance: str) -> HostLatch:
    """Give ``server`` the latch: the middleware and ``/latch``."""
    latch = HostLatch(instance)
    server.add_middleware(LatchMiddleware(latch, ReadOnlyTools(server)))
    server.custom_route(LATCH_PATH, methods=["GET", "POST"])(latch_endpoint(latch))
    return latch
