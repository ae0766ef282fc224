"""The confirmation routes: workers ask, people answer (web buttons, scripts), everyone can list.

Registered on the protected router of :mod:`rosaos.kernel.api.routes` (the bearer token applies).
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import HTTPException, Query

from rosaos.confirmations.confirmation_desk import (
    Confirmation,
    ConfirmationAnswer,
    ConfirmationList,
    ConfirmationRequest,
)
from rosaos.kernel.api.routes import Runtime, protected

MAX_WAIT = 30.0


@protected.post("/confirmations", status_code=201)
async def ask_confirmation(body: ConfirmationRequest, runtime: Runtime) -> Confirmation:
    """A worker asks before a call that needs a yes; the kernel asks the person (chat, web, voice)."""
    running = {
        _field(process, "id")
        for process in await runtime.processes()
        if _field(process, "state") == "running"
    }
    if body.process_id not in running:
        raise HTTPException(404, f"no running process {body.process_id}; only a running process can ask")
    return await runtime.confirmations.ask(body)


def _field(process: Any, name: str) -> Any:
    """A field of a process as ``runtime.processes()`` gives it (a model, an object or a dict)."""
    return process.get(name) if isinstance(process, dict) else getattr(process, name, None)


@protected.get("/confirmations")
async def list_confirmations(
    runtime: Runtime,
    include_answered: Annotated[bool, Query(alias="all", description="Add recent answered ones.")] = False,
) -> ConfirmationList:
    """The pending questions, oldest first."""
    desk = runtime.confirmations
    return ConfirmationList(confirmations=desk.all() if include_answered else desk.pending())


@protected.get("/confirmations/{confirmation_id}")
async def get_confirmation(
    confirmation_id: int,
    runtime: Runtime,
    wait: Annotated[float, Query(ge=0, le=MAX_WAIT, description="Seconds to wait for an answer.")] = 0.0,
) -> Confirmation:
    """One question; with ``wait``, answers as soon as it is settled (long poll)."""
    try:
        return await runtime.confirmations.wait(confirmation_id, wait)
    except KeyError:
        raise HTTPException(
            404, f"no confirmation {confirmation_id}; GET /confirmations lists them"
        ) from None


@protected.post("/confirmations/{confirmation_id}")
async def answer_confirmation(
    confirmation_id: int, body: ConfirmationAnswer, runtime: Runtime
) -> Confirmation:
    """Answer a pending question: ``{"answer": "yes"}`` runs the call, ``"no"`` cancels the process."""
    try:
        return runtime.confirmations.answer(confirmation_id, body.answer, by="api")
    except KeyError:
        raise HTTPException(
            404, f"no confirmation {confirmation_id}; GET /confirmations lists them"
        ) from None
    except ValueError as settled:
        raise HTTPException(409, str(settled)) from None
