"""The kernel's HTTP API: the FastAPI app that serves the routes, and the rules around them.

``create_app(runtime)`` builds the FastAPI app; ``rosaos up`` serves it with uvicorn on loopback.
The routes are in :mod:`rosaos.kernel.api.routes`; what they take and answer, and what they need
from the kernel (:class:`KernelRuntime`), in :mod:`rosaos.kernel.api.schemas`. Every route needs
``Authorization: Bearer <token>`` except ``/health``, the web page and its assets, ``/login``, and
the API docs (``/docs``, ``/openapi.json``). Browser requests from another origin are refused with
403 before anything else runs. Errors are JSON with a ``detail`` that says what went wrong.
"""

from __future__ import annotations

import re
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from fastapi.staticfiles import StaticFiles
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.responses import Response

import rosaos
import rosaos.confirmations.confirmation_routes
import rosaos.timers.timer_routes
from rosaos.auth import BearerAuthMiddleware, HostOriginGuard
from rosaos.kernel.api import (
    control_routes,  # noqa: F401  (adds its routes to protected)
    frame_routes,  # noqa: F401  (adds its routes to protected)
    memory_routes,  # noqa: F401  (adds its routes to protected)
)
from rosaos.kernel.api.routes import KERNEL_ONLY, WEB_DIR, protected, public
from rosaos.kernel.api.schemas import KernelRuntime

MAX_BODY_BYTES = 1_000_000
"""Larger request bodies get 413; a worker's output is the biggest thing anyone posts."""


async def _invalid_request(request: Request, error: Exception) -> JSONResponse:
    assert isinstance(error, RequestValidationError)
    problems = [_problem(problem) for problem in error.errors()]
    summary = "; ".join(f"{'.'.join(problem['loc'])}: {problem['msg']}" for problem in problems)
    return JSONResponse({"detail": f"invalid request: {summary}", "errors": problems}, status_code=422)


def _problem(problem: Mapping[str, Any]) -> dict[str, Any]:
    loc = [str(part) for part in problem["loc"]]
    message = problem["msg"]
    if problem["type"] == "json_invalid":
        # FastAPI puts the character offset in loc and the parser's reason in ctx; say it plainly.
        reason = problem.get("ctx", {}).get("error", "")
        message = f"not valid JSON: {reason} (at character {loc[1]})" if len(loc) > 1 else message
        loc = loc[:1]
    tag = problem.get("ctx", {}).get("tag") if problem["type"] == "union_tag_invalid" else None
    if tag in KERNEL_ONLY:  # a kind only the kernel queues (POST /event): say why, not just "invalid"
        message = f"{tag} events are not accepted here: {KERNEL_ONLY[tag]}"
    return {"loc": loc, "msg": message, "type": problem["type"]}


async def _internal_error(request: Request, error: Exception) -> JSONResponse:
    return JSONResponse(
        {"detail": f"internal error ({type(error).__name__}): see the rosaOS kernel log"}, status_code=500
    )


def create_app(
    runtime: KernelRuntime,
    *,
    allowed_origins: Iterable[str] = (),
    allowed_hosts: Iterable[str] = (),
    images_dir: Path | None = None,
) -> FastAPI:
    """The kernel's FastAPI app. ``allowed_origins`` adds browser origins besides the server's own;
    ``allowed_hosts`` adds ``Host`` names besides loopback; ``images_dir`` is where drivers save
    camera frames (the web page shows the newest of each device)."""
    app = FastAPI(
        title="rosaOS kernel",
        version=rosaos.__version__,
        summary="Events in, updates out: the kernel of an agentic operating system for robots.",
        max_body_size=MAX_BODY_BYTES,
    )
    app.state.runtime = runtime
    app.state.started = time.monotonic()
    app.state.images_dir = images_dir
    app.include_router(public)
    app.include_router(protected)
    app.mount("/static", StaticFiles(directory=WEB_DIR), name="static")
    app.add_exception_handler(RequestValidationError, _invalid_request)
    app.add_exception_handler(Exception, _internal_error)
    app.add_exception_handler(StarletteHTTPException, _http_error)
    assets = [f"/static/{path.name}" for path in WEB_DIR.iterdir() if path.is_file()]
    open_paths = ["/", "/health", "/login", "/docs", "/openapi.json", *assets]
    # Added last = runs first: foreign hosts and origins are refused before the token is looked at.
    app.add_middleware(BearerAuthMiddleware, token=runtime.token, open_paths=open_paths)
    app.add_middleware(HostOriginGuard, allowed_hosts=allowed_hosts, allowed_origins=allowed_origins)
    return app


async def _http_error(request: Request, error: Exception) -> Response:
    """FastAPI's answer, except that a 405 lists every method of the path in ``Allow``.

    The router stops at the first route whose path matches, so ``OPTIONS /estop`` would say
    ``Allow: GET`` although ``POST /estop`` exists too. The published paths know them all."""
    assert isinstance(error, StarletteHTTPException)
    response = await http_exception_handler(request, error)
    if error.status_code == 405:
        methods = {
            method.upper()
            for template, operations in request.app.openapi()["paths"].items()
            if re.fullmatch(re.sub(r"\\\{[^}]+\\\}", "[^/]+", re.escape(template)), request.url.path)
            for method in operations
        }
        if methods:
            response.headers["Allow"] = ", ".join(sorted(methods))
    return response
