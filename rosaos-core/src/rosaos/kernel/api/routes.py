"""The kernel's HTTP routes: events in, updates out, processes, devices, the emergency stop, the web page.

Two routers, included by :func:`rosaos.kernel.api.app.create_app` in this order: ``public`` (open to
anyone who can reach the port: ``/health``, ``/login`` and the web page) and ``protected`` (the
rest; ``BearerAuthMiddleware`` enforces the token, the router only documents it in OpenAPI).
Events (``POST /chat``, ``POST /stt``, ``POST /event``) go through the kernel's intake
(:mod:`rosaos.kernel.intake`) and are answered ``202 {"id", "duplicate"}`` only after the commit.
"""

from __future__ import annotations

import hmac
import logging
import time
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Header, HTTPException, Query, Request
from fastapi import Path as FastPath
from fastapi.responses import FileResponse, Response
from fastapi.security import HTTPBearer
from sse_starlette import EventSourceResponse, ServerSentEvent

import rosaos
from rosaos.events.types import Event, ExternalEvent, NewEvent, UserSaidEvent, UserText, UserTypedEvent
from rosaos.kernel.activity import DEFAULT_LIMIT as DEFAULT_ACTIVITY
from rosaos.kernel.activity import MAX_LIMIT as MAX_ACTIVITY
from rosaos.kernel.activity import ActivityPage
from rosaos.kernel.api.login_codes import login_url
from rosaos.kernel.api.schemas import (
    COMMON_ERRORS,
    PROTECTED_ERRORS,
    Accepted,
    DeviceView,
    EmergencyStopReport,
    EmergencyStopRequest,
    EmergencyStopState,
    Health,
    KernelRuntime,
    LoginLink,
    LoginRequest,
    LoginToken,
    ProcessView,
    SayRequest,
    Understanding,
    UnderstandRequest,
    UpdatesPage,
)
from rosaos.kernel.updates import UpdateStream

log = logging.getLogger(__name__)

WEB_DIR = Path(__file__).resolve().parents[2] / "frontends" / "web"
SSE_PING_SECONDS = 15
SSE_SEND_TIMEOUT = 30.0
"""A client that takes longer than this to accept one message is dropped (it reconnects and resumes)."""
SSE_RETRY_MS = 2000


async def _runtime(request: Request) -> KernelRuntime:  # async: no thread hop per request
    runtime: KernelRuntime = request.app.state.runtime
    return runtime


Runtime = Annotated[KernelRuntime, Depends(_runtime)]
MAX_ID = 2**53 - 1
"""The largest id the API accepts: below SQLite's 2**63 - 1 (a larger one would overflow the
query), and exact as a JSON number in every client. A bound of 2**63 - 1 read as a double is
2**63, so clients (and schema-driven test generators) would send ids the API then refuses."""
IdempotencyHeader = Annotated[str | None, Header(alias="Idempotency-Key", max_length=200)]

# Documents the token in OpenAPI (the /docs "Authorize" button); BearerAuthMiddleware enforces it.
_bearer_docs = HTTPBearer(auto_error=False, description="The token from <data_dir>/token.")
public = APIRouter(responses=COMMON_ERRORS)
protected = APIRouter(dependencies=[Depends(_bearer_docs)], responses=PROTECTED_ERRORS)


@public.get("/health")
async def health(request: Request, runtime: Runtime) -> Health:
    """Liveness, version, model and readiness, for monitors, scripts (`rosaos ready`) and the web
    page before login. No token needed; with it, the devices still starting are named."""
    readiness = runtime.readiness()
    presented = request.headers.get("authorization", "").removeprefix("Bearer ").strip()
    if not hmac.compare_digest(presented.encode(), runtime.token.encode()):
        readiness = readiness.model_copy(update={"starting": None})
    return Health(
        **readiness.model_dump(),
        version=rosaos.__version__,
        model=runtime.model_description,
        model_notice=runtime.model_notice,
        uptime_seconds=round(time.monotonic() - request.app.state.started, 3),
        pending_events=await runtime.events.pending_count(),
    )


@public.post(
    "/login",
    responses={
        400: PROTECTED_ERRORS[400] | {"description": "A body that is not UTF-8 JSON"},
        401: PROTECTED_ERRORS[401] | {"description": "An unknown, expired or used login code"},
    },
)
async def login(body: LoginRequest, runtime: Runtime, response: Response) -> LoginToken:
    """Trade a one-time login code (from ``#login=`` in the printed link) for the bearer token."""
    response.headers["Cache-Control"] = "no-store"
    if not runtime.login_codes.redeem(body.code):
        raise HTTPException(
            401,
            "this login link is unknown, expired or already used: "
            "run `rosaos open` on the machine where rosaOS runs for a fresh link "
            "(`rosaos open --browser` opens it)",
        )
    return LoginToken(token=runtime.token)


@protected.post("/login-codes", status_code=201)
async def mint_login_code(request: Request, runtime: Runtime) -> LoginLink:
    """A new one-time login link for the web page (the CLI prints it)."""
    code = runtime.login_codes.mint()
    base = str(request.base_url)
    return LoginLink(code=code, url=login_url(base, code), expires_in=runtime.login_codes.lifetime)


@protected.post("/chat", status_code=202)
async def chat(body: SayRequest, runtime: Runtime, idempotency_key: IdempotencyHeader = None) -> Accepted:
    """The user typed something: enqueue a ``user_typed`` event."""
    fields = _user_text(body, "chat", idempotency_key)
    return await _accept(runtime, UserTypedEvent(kind="user_typed", **fields))


@protected.post("/stt", status_code=202)
async def speech(body: SayRequest, runtime: Runtime, idempotency_key: IdempotencyHeader = None) -> Accepted:
    """The voice front end heard the user: enqueue a ``user_said`` event."""
    fields = _user_text(body, "stt", idempotency_key)
    return await _accept(runtime, UserSaidEvent(kind="user_said", **fields))


@protected.post("/understand")
async def understand(body: UnderstandRequest, runtime: Runtime) -> Understanding:
    """Would the offline engine act on this sentence as it stands? Nothing is queued or run.

    The voice front end asks this of its draft transcript to end a turn after a short pause when
    the command is already whole, and to wait longer when it is not ("turn on the …").
    """
    return await runtime.understand(body.text)


def _user_text(body: SayRequest, default_source: str, header_key: str | None) -> dict[str, Any]:
    """The fields ``/chat`` and ``/stt`` events share: source, the text, the idempotency key."""
    return {
        "source": body.source or default_source,
        "payload": UserText(text=body.text),
        "idempotency_key": _key(body.idempotency_key, header_key),
    }


KERNEL_ONLY = {
    "worker_callback": "a process's end comes from its worker over the pool's pipe",
    "timer_fired": 'timers fire from the kernel\'s own table; ask for one in words (POST /chat "in 10 minutes, …")',
}
"""Kinds only the kernel itself queues: one posted from outside would be a second, racing source."""


@protected.post("/event", status_code=202)
async def post_event(
    event: ExternalEvent, runtime: Runtime, idempotency_key: IdempotencyHeader = None
) -> Accepted:
    """Enqueue an event from outside the kernel (a script, a home-automation hook), told apart by
    ``kind``: ``user_said``, ``user_typed``, ``device_notice`` or ``error``. The published schema
    lists only these; a ``KERNEL_ONLY`` kind is refused with its reason (``app._problem``)."""
    key = _key(event.idempotency_key, idempotency_key)
    return await _accept(runtime, event.model_copy(update={"idempotency_key": key}))


@protected.get("/events/{event_id}")
async def get_event(event_id: Annotated[int, FastPath(ge=1, le=MAX_ID)], runtime: Runtime) -> Event:
    """One event, and whether the kernel has handled it."""
    event = await runtime.events.get(event_id)
    if event is None:
        raise HTTPException(404, f"no event {event_id}: ids come from the 202 answer of POST /event")
    return event


@protected.get(
    "/updates",
    responses={200: {"content": {"text/event-stream": {"schema": {"type": "string"}}}}},
)
async def get_updates(
    request: Request,
    runtime: Runtime,
    after: Annotated[int | None, Query(ge=0, le=MAX_ID, description="Only updates with a larger id.")] = None,
    limit: Annotated[int, Query(ge=1, le=1000, description="At most this many (per page or backlog).")] = 100,
    last_event_id: Annotated[
        str | None,
        Header(
            alias="Last-Event-ID",
            pattern=r"^(\d{1,18}|null)?$",
            description="The last update id seen (SSE reconnects); empty or null for none.",
        ),
    ] = None,
) -> Any:
    """The updates stream: server-sent events with ``Accept: text/event-stream``, else one JSON page.

    Both start after ``Last-Event-ID`` (SSE reconnects), else after ``?after=``, else with the
    last ``limit`` updates. The SSE stream then follows new updates until the client leaves.
    """
    if last_event_id is not None and last_event_id.strip().lower() not in ("", "null"):
        # A client that never saw an update may send an empty or "null" id: that is no id.
        after = int(last_event_id)  # the pattern allows only digits here
    updates = runtime.updates
    newest = await updates.last_id()
    if after is not None and after > newest:
        after = None  # a cursor from an older store (the data directory was reset): start afresh
    if after is None:
        recent = await updates.recent(limit)
        after = recent[0].id - 1 if recent else newest
    if "text/event-stream" not in request.headers.get("accept", ""):
        page = await updates.after(after, limit)
        return UpdatesPage(updates=page, last_id=page[-1].id if page else after)
    return EventSourceResponse(_stream(updates, after), ping=SSE_PING_SECONDS, send_timeout=SSE_SEND_TIMEOUT)


async def _stream(updates: UpdateStream, after: int) -> AsyncIterator[ServerSentEvent]:
    yield ServerSentEvent(comment="rosaOS updates", retry=SSE_RETRY_MS)
    async for update in updates.follow(after):
        yield ServerSentEvent(data=update.model_dump_json(), id=str(update.id))


@protected.get("/activity")
async def list_activity(
    runtime: Runtime,
    device: Annotated[str | None, Query(max_length=100, description="Only this device's calls.")] = None,
    process: Annotated[int | None, Query(ge=1, le=MAX_ID, description="Only this process's calls.")] = None,
    since: Annotated[
        float | None, Query(ge=0, description="Only calls started at or after this time (epoch seconds).")
    ] = None,
    limit: Annotated[
        int, Query(ge=1, le=MAX_ACTIVITY, description="The newest this many.")
    ] = DEFAULT_ACTIVITY,
) -> ActivityPage:
    """The activity log: every tool call of the processes, with its result and safety decision."""
    entries = await runtime.activity.query(device=device, process_id=process, since=since, limit=limit)
    return ActivityPage(entries=entries)


@protected.get("/processes")
async def list_processes(
    runtime: Runtime,
    include_ended: Annotated[
        bool, Query(alias="all", description="Include processes that have ended.")
    ] = False,
) -> list[ProcessView]:
    """The process agents and the devices they hold."""
    return [ProcessView.model_validate(process) for process in await runtime.processes(include_ended)]


@protected.get("/estop")
async def emergency_stop_state(runtime: Runtime) -> EmergencyStopState:
    """Whether the emergency stop is latched, why, and since when (kept across kernel restarts)."""
    return runtime.emergency_stop_state()


@protected.post("/estop")
async def emergency_stop(runtime: Runtime, body: EmergencyStopRequest | None = None) -> EmergencyStopReport:
    """Emergency stop: terminate every process, put every device in its safe state, and refuse
    new processes until a person resets it (``POST /estop/reset``)."""
    return await runtime.emergency_stop((body or EmergencyStopRequest()).reason)


@protected.post("/estop/reset")
async def reset_emergency_stop(runtime: Runtime) -> EmergencyStopState:
    """Unlatch the emergency stop, on disk too: the next start is unlatched."""
    return await runtime.reset_emergency_stop()


@protected.post("/processes/{process_id}/terminate")
async def terminate_process(
    process_id: Annotated[int, FastPath(ge=1, le=MAX_ID)], runtime: Runtime
) -> ProcessView:
    """Kill a running process and release its devices. An ended process is returned as it is."""
    try:
        process = await runtime.terminate(process_id)
    except KeyError:
        raise HTTPException(404, f"no process {process_id}: GET /processes lists the running ones") from None
    return ProcessView.model_validate(process)


@protected.get("/devices")
async def list_devices(runtime: Runtime) -> list[DeviceView]:
    """Every device instance, its status and its live state."""
    return [DeviceView.model_validate(device) for device in await runtime.devices()]


@public.get("/", include_in_schema=False)
async def web_page() -> FileResponse:
    """The web page. Public, but useless without a login code."""
    return FileResponse(WEB_DIR / "index.html", headers=PAGE_HEADERS)


PAGE_HEADERS = {
    "Cache-Control": "no-cache",
    "Content-Security-Policy": (
        "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; "
        "connect-src 'self'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'"
    ),
    "Referrer-Policy": "no-referrer",
    "X-Content-Type-Options": "nosniff",
}


def _key(in_body: str | None, in_header: str | None) -> str | None:
    if in_body and in_header and in_body != in_header:
        raise HTTPException(409, "the Idempotency-Key header and the body's idempotency_key differ; send one")
    return in_body or in_header or None


async def _accept(runtime: KernelRuntime, event: NewEvent) -> Accepted:
    queued = await runtime.intake.submit(event)
    if queued.conflict:
        raise HTTPException(
            409,
            f"idempotency key {event.idempotency_key!r} was already used for event {queued.id} with a "
            "different body; use a new key for a new request",
        )
    return Accepted(id=queued.id, duplicate=queued.duplicate)
