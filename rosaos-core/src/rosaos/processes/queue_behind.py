"""A launch waits behind a short process that holds its device, instead of being refused.

A person who speaks quickly says "turn on the lamp" and, a moment later, "actually, make it
green": the second sentence arrives while the first one's process still holds the lamp. Refusing
it ("lamp is held by process 15; wait for it") asks the user to repeat what they said a second
ago. So a launch refused only because exclusive devices are held waits, with a bound, for the
holders to end, then takes the leases and runs, once, after them.

Only behind a *short* holder: a plan of device actions (the offline engine's, with no follow-up
waiting on it) that has reported no progress. A process without a plan (an LLM's), a plan whose
success launches more, or a long task (a device tool that reports progress, such as a robot's
search) is answered at once as before: the kernel may wait, ask, or terminate it.

"stop" still wins: a holder that ends ``terminated`` (a stop, a terminate) cancels the waiting
launch, which is refused saying so; nothing queued runs after a stop. The bound keeps a turn from
waiting on a holder that turns out slow: it is refused as before, saying how long it waited.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from rosaos.processes.leases import LeaseRefused

if TYPE_CHECKING:
    from rosaos.processes.manager import ProcessInfo

QUEUE_WAIT = 12.0
"""Seconds a launch waits behind short holders before it is refused as held."""
_POLL = 0.05


class Refused(Exception):
    """The launch does not wait, or waited in vain; the message says why and what to do."""


def short(info: ProcessInfo) -> bool:
    """Whether a running process is a short plan of device actions (see the module docstring)."""
    return (
        info.state == "running" and info.plan is not None and info.plan.then is None and info.progress is None
    )


async def wait_behind(
    refusal: LeaseRefused, lookup: Callable[[int], ProcessInfo], bound: float = QUEUE_WAIT
) -> list[int]:
    """Wait until every process ``refusal`` names as a holder has ended; return their ids.

    ``lookup(process_id)`` is the manager's :meth:`~rosaos.processes.manager.ProcessManager.get`.
    Raises :class:`Refused` at once when the refusal is not only about held devices or a holder is
    not short, and later when a holder is stopped, turns out to be a long task, or outlasts ``bound``.
    """
    message = str(refusal)
    holders = sorted({lease.process_id for lease in refusal.holders.values()})
    if not holders or len(message.splitlines()) != len(refusal.holders):
        raise Refused(message)
    if not all(short(lookup(process_id)) for process_id in holders):
        raise Refused(message)
    deadline = time.monotonic() + bound
    while True:
        infos = [lookup(process_id) for process_id in holders]
        stopped = [info.id for info in infos if info.state == "terminated"]
        if stopped:
            raise Refused(
                f"process {stopped[0]}, which held the device, was stopped while this waited for it, "
                "so this was not started; say it again to run it now"
            )
        running = [info for info in infos if info.state == "running"]
        if not running:
            return holders
        if any(info.progress is not None for info in running):
            raise Refused(message)  # a long task after all: the kernel decides, as before
        if time.monotonic() >= deadline:
            raise Refused(f"{message}\n(it was still running after waiting {bound:g} s for it)")
        await asyncio.sleep(_POLL)
