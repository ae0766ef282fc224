"""Processes a dead kernel left behind: remembered while they run, made safe and reported on restart.

A process is written to the event store when it is launched — after its leases are granted and
*before* any worker is told to start, with the event and step that launched it — and removed when
its end is recorded. The cause is kept longer (:data:`CAUSES_KEPT` launches): when the event is
handled again after a crash, the same launch is refused (:mod:`rosaos.kernel.launch_cause`).
A kernel killed with ``kill -9`` removes nothing, so at the next start the store still lists the
processes that were running. Their workers died with the old kernel (they watch its pipe and stop
their devices), but the kernel does not take that on trust: before its loop grants anything,
:func:`recover_orphans` calls ``safe_stop`` on every device such a process held, then reports each
process as ``crashed (kernel restarted)`` with its task, as a worker callback, so the kernel model
(or the user, reading the chat) can decide whether to try again.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable, Mapping
from datetime import datetime
from typing import Any

from pydantic import BaseModel, ValidationError

from rosaos.devices.supervisor import DirectoryEntry, SafeStopOutcome, safe_stop_entry
from rosaos.events.callback import WorkerCallback, callback_idempotency_key
from rosaos.events.plan import Plan
from rosaos.events.types import NewEvent, WorkerCallbackEvent
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.intake import Queued
from rosaos.kernel.launch_cause import LaunchCause
from rosaos.processes.manager import ProcessInfo

log = logging.getLogger("rosaos.kernel.orphans")

LIVE_PROCESSES_KEY = "live_processes"
LAUNCH_CAUSES_KEY = "launch_causes"
"""``"event:step"`` → process id, for the last :data:`CAUSES_KEPT` launches."""
CAUSES_KEPT = 2000
RESTART_ERROR = "kernel restarted"
"""The error of a process a dead kernel left: with status ``crashed`` it reads ``crashed (kernel restarted: …)``."""


class LiveProcess(BaseModel):
    """A running process, as the store remembers it."""

    id: int
    task: str
    devices: list[str]
    started_at: datetime
    plan: Plan | None = None
    then: str | None = None
    event_id: int | None = None
    """The event whose handling launched it (None: launched outside the loop)."""
    step: int | None = None


class LiveProcesses:
    """The store's list of running processes (the ``live_processes`` value).

    The store is the truth across a crash; this kernel is its only writer, so it reads it once and
    then keeps a copy, each record also kept as it is written. A launch or an end then parses and
    validates one record, not every live process and every remembered cause (at a burst of 300
    commands that was most of the kernel's work per event)."""

    def __init__(self, store: EventStore) -> None:
        self._store = store
        self._lock = asyncio.Lock()  # launches and ends interleave at awaits
        self._live: dict[int, LiveProcess] | None = None
        self._written: dict[str, dict[str, Any]] = {}  # the same, as stored
        self._kept_causes: dict[str, Any] | None = None

    async def launched(self, info: ProcessInfo, cause: LaunchCause | None = None) -> None:
        """Remember a process that is being launched, and what launched it: call before it starts.

        Its id (never given again, also after a restart), the process and its cause are one commit.
        """
        async with self._lock:
            live = await self._read()
            process = LiveProcess(
                id=info.id,
                task=info.task,
                devices=info.devices,
                started_at=info.started_at,
                plan=info.plan,
                then=info.then,
                event_id=cause.event_id if cause else None,
                step=cause.step if cause else None,
            )
            live[info.id] = process
            self._written[str(info.id)] = process.model_dump(mode="json")
            values: dict[str, Any] = {LIVE_PROCESSES_KEY: self._written}
            if cause is not None:
                causes = await self._causes()
                causes[_cause_key(cause)] = info.id
                while len(causes) > CAUSES_KEPT:
                    del causes[next(iter(causes))]
                values[LAUNCH_CAUSES_KEY] = causes
            await self._store.set_values(values, note_process_id=info.id)

    async def launched_for(self, cause: LaunchCause) -> int | None:
        """The process a launch with this cause started before, if the store remembers one."""
        process_id = (await self._causes()).get(_cause_key(cause))
        return process_id if isinstance(process_id, int) else None

    async def _causes(self) -> dict[str, Any]:
        if self._kept_causes is None:
            stored = await self._store.get_value(LAUNCH_CAUSES_KEY)
            self._kept_causes = dict(stored) if isinstance(stored, dict) else {}
        return self._kept_causes

    async def ended(self, process_id: int) -> None:
        """Forget a process whose end was recorded."""
        async with self._lock:
            live = await self._read()
            if live.pop(process_id, None) is not None:
                self._written.pop(str(process_id), None)
                await self._write()

    async def left(self) -> list[LiveProcess]:
        """The processes the store lists as running: at start-up, those a dead kernel left."""
        return sorted((await self._read()).values(), key=lambda p: p.id)

    async def _read(self) -> dict[int, LiveProcess]:
        if self._live is not None:
            return self._live
        stored = await self._store.get_value(LIVE_PROCESSES_KEY) or {}
        live = {}
        for raw in stored.values() if isinstance(stored, dict) else []:
            try:
                process = LiveProcess.model_validate(raw)
            except ValidationError:
                log.error("ignoring an unreadable live process record: %r", raw)
                continue
            live[process.id] = process
            self._written[str(process.id)] = process.model_dump(mode="json")
        self._live = live
        return live

    async def _write(self) -> None:
        await self._store.set_value(LIVE_PROCESSES_KEY, self._written)


async def recover_orphans(
    live: LiveProcesses,
    directory: Mapping[str, DirectoryEntry],
    enqueue: Callable[[NewEvent], Awaitable[Queued]],
    remember: Callable[[ProcessInfo], None] | None = None,
) -> list[SafeStopOutcome]:
    """``safe_stop`` every device a left-behind process held, then report each process as crashed.

    Call it after the devices started and before the kernel loop runs, so nothing is granted
    before its device is safe. ``enqueue`` is the kernel's intake: the crash is queued as any
    process's end is, with the same idempotency key, so an end the process itself got committed
    before the kernel died is kept instead (the intake answers with the first event).
    """
    orphans = await live.left()
    if not orphans:
        return []
    for process in orphans:  # listed by `rosaos ps --all` until this kernel stops
        if remember is not None:
            remember(
                ProcessInfo(
                    id=process.id,
                    task=process.task,
                    devices=process.devices,
                    state="running",
                    started_at=process.started_at,
                )
            )
    held = sorted({name for process in orphans for name in process.devices if name in directory})
    outcomes = list(await asyncio.gather(*(safe_stop_entry(directory[name]) for name in held)))
    stops = {outcome.instance: outcome for outcome in outcomes}
    for process in orphans:
        stopped = ", ".join(
            f"{name} {'safe-stopped' if stops[name].ok else 'NOT safe-stopped: ' + stops[name].detail}"
            for name in process.devices
            if name in stops
        )
        callback = WorkerCallback(
            process_id=process.id,
            status="crashed",
            error=f"{RESTART_ERROR}: the kernel stopped while this process ran"
            + (f"; {stopped}" if stopped else ""),
            task=process.task,
            plan=process.plan,
            then=None if process.plan is not None else process.then,
        )
        event = WorkerCallbackEvent(
            kind="worker_callback",
            source="kernel",
            payload=callback,
            idempotency_key=callback_idempotency_key(process.id),
        )
        await enqueue(event)
        await live.ended(process.id)
        log.warning("process %d (%s): %s", process.id, process.task, callback.error)
    return outcomes


def _cause_key(cause: LaunchCause) -> str:
    return f"{cause.event_id}:{cause.step}"
