"""The timer routes: ``GET /timers`` lists them, ``DELETE /timers/{id}`` cancels one.

Registered on the protected router of :mod:`rosaos.kernel.api.routes` (the bearer token applies).
Timers are set by the kernel agent's ``set_timer`` tool ("turn off the light in ten minutes"),
so there is no route to set one: say it to the kernel with ``POST /chat``.
"""

from __future__ import annotations

from typing import Annotated

from fastapi import HTTPException, Query
from fastapi import Path as FastPath

from rosaos.kernel.api.routes import MAX_ID, Runtime, protected
from rosaos.timers.timer_book import Timer, TimerError, TimerList


@protected.get("/timers")
async def list_timers(
    runtime: Runtime,
    include_settled: Annotated[
        bool, Query(alias="all", description="Add the last 50 fired or cancelled timers.")
    ] = False,
) -> TimerList:
    """The pending timers, soonest first; with ``all=true``, recent fired and cancelled ones after them."""
    return TimerList(timers=await runtime.timers.list_timers(include_settled), now=runtime.timers.now())


@protected.delete("/timers/{timer_id}")
async def cancel_timer(timer_id: Annotated[int, FastPath(ge=1, le=MAX_ID)], runtime: Runtime) -> Timer:
    """Cancel a pending timer so it never fires; 409 if it has already fired or been cancelled."""
    try:
        timer = await runtime.timers.cancel(timer_id)
    except KeyError:
        raise HTTPException(404, f"no timer {timer_id}; GET /timers lists them") from None
    except TimerError as settled:
        raise HTTPException(409, str(settled)) from None
    # Other pages and the CLI chat follow the updates stream: tell them, as the kernel would.
    data = {"timer": timer.model_dump(mode="json")}
    await runtime.updates.publish("notice", f"timer {timer.id} cancelled: {timer.action}", data)
    return timer
