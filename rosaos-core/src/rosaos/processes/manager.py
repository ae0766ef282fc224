"""The process manager: what the kernel agent's tools call to launch, list and terminate processes.

``launch`` takes the leases first (a refusal never reaches the pool), then hands the job to the
worker pool and returns at once with the process id. A process's end has one route: the pool
reports it (``done`` message, crash, timeout, terminate) through its ``on_ended``, exactly once.
The manager marks the process ended, releases its leases, and passes the callback on to the
kernel's ``on_ended``, which enqueues it as a ``worker_callback`` event.
"""

from __future__ import annotations

import asyncio
import builtins
import contextlib
import logging
from collections.abc import Awaitable, Callable, Mapping
from datetime import UTC, datetime
from typing import Literal

from pydantic import BaseModel, Field

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.events.callback import WorkerCallback
from rosaos.events.plan import Plan
from rosaos.models.select import ModelSpec
from rosaos.processes.forking import preload_modules
from rosaos.processes.jobs import GrantedDevice, WorkerJob
from rosaos.processes.leases import LeaseRefused, LeaseTable
from rosaos.processes.pool import PoolError, WorkerPool
from rosaos.processes.protocol import Progress

log = logging.getLogger("rosaos.processes.manager")

STARTING_WAIT = 15.0
"""Seconds a launch waits for a device that is still starting before it is refused (as not available)."""

ProcessState = Literal["running", "ok", "error", "crashed", "timeout", "terminated", "unverified"]


class ProcessProgress(BaseModel):
    """The latest progress a process's device tool reported (a long task such as a search)."""

    device: str
    progress: float
    total: float | None = None
    message: str = ""
    at: datetime

    @property
    def percent(self) -> int | None:
        """0-100 when the tool gave a total, else None."""
        if not self.total:
            return None
        return max(0, min(100, round(100 * self.progress / self.total)))


class ProcessInfo(BaseModel):
    """One process, as ``list_processes`` shows it."""

    id: int
    task: str
    devices: list[str]
    state: ProcessState
    then: str | None = None
    """What the kernel launches when this process succeeds, in words (its plan's or an LLM's)."""
    plan: Plan | None = Field(default=None, exclude=True)
    """The offline engine's plan, kept for a callback the kernel writes itself; not listed."""
    started_at: datetime
    ended_at: datetime | None = None
    worker_pid: int | None = None
    progress: ProcessProgress | None = None
    """The latest progress of a long task, while it runs."""


class EmergencyStop(BaseModel):
    """A latched emergency stop: why, and when it was (last) pressed."""

    reason: str
    time: datetime


class LaunchRefused(Exception):
    """A process that was not launched; the message says why and what to do instead."""


class ProcessManager:
    """Launches processes on the worker pool under device leases, and tracks them until they end."""

    def __init__(
        self,
        *,
        devices: Callable[[], Mapping[str, DeviceEndpoint]],
        model: ModelSpec,
        base_prompt: str,
        job_timeout: float,
        request_limit: int,
        kernel_url: str,
        kernel_token: str,
        pool: WorkerPool,
        on_ended: Callable[[WorkerCallback], Awaitable[None]],
        first_process_id: int = 1,
        emergency_stop: EmergencyStop | None = None,
        starting: Callable[[builtins.list[str]], Awaitable[None]] | None = None,
        starting_wait: float = STARTING_WAIT,
    ) -> None:
        if first_process_id < 1:
            raise ValueError("first_process_id must be 1 or more")
        self._devices = devices
        self._model = model
        self._base_prompt = base_prompt
        self._job_timeout = job_timeout
        self._request_limit = request_limit
        self._kernel_url = kernel_url
        self._kernel_token = kernel_token
        self._pool = pool
        self._on_ended = on_ended
        self._next_id = first_process_id
        self._processes: dict[int, ProcessInfo] = {}
        self.leases = LeaseTable()
        self._starting = starting
        self.warming: asyncio.Task[None] | None = None
        """The pool's start, when :meth:`start_in_background` began it."""
        """Waits until the named devices have had their first start attempt (the supervisor's ``settle``)."""
        self.starting_wait = starting_wait
        self.emergency_stop = emergency_stop
        """The latched emergency stop, or None. While latched every launch is refused. The kernel
        keeps it on disk and passes it in at start, so a restart does not unlatch it."""
        pool.on_ended = self._worker_ended
        pool.on_progress = self.record_progress
        pool.on_started = self._worker_started
        pool.preload.extend(preload_modules(model))

    @property
    def pool(self) -> WorkerPool:
        """The worker pool; the manager has taken over its ``on_ended``."""
        return self._pool

    @property
    def next_process_id(self) -> int:
        """The id the next launch will get."""
        return self._next_id

    async def start(self) -> None:
        """Start the worker pool (its warm workers are ready when this returns)."""
        await self._pool.start()

    def start_in_background(self) -> asyncio.Task[None]:
        """Start the worker pool without waiting for it; a launch meanwhile waits for it.

        ``rosaos up`` shows its banner while the fork server still imports: a command typed at
        once is queued for the warm pool, instead of exec'ing workers that import everything
        again. The task fails with :class:`PoolError` when the pool cannot start."""
        self.warming = asyncio.create_task(self._pool.start(), name="start worker pool")
        return self.warming

    async def stop(self) -> None:
        """Terminate every running process, release every lease, and stop the pool."""
        if self.warming is not None and not self.warming.done():
            self.warming.cancel()
            await asyncio.gather(self.warming, return_exceptions=True)
        for info in self.list():
            await self.terminate(info.id)
        await self._pool.stop()
        for process_id in list(self._processes):
            self.leases.release(process_id)

    async def latch_emergency_stop(self, reason: str) -> builtins.list[ProcessInfo]:
        """Latch the emergency stop and terminate every running process; return what was stopped.

        Stopping again while latched stops everything again and replaces the reason and time.
        """
        self.emergency_stop = EmergencyStop(reason=reason, time=_now())
        stopped = []
        for info in self.list():
            stopped.append(await self.terminate(info.id))
        return stopped

    def reset_emergency_stop(self) -> None:
        """Unlatch: processes may be launched again."""
        self.emergency_stop = None

    async def launch(
        self,
        task: str,
        devices: builtins.list[str],
        before_start: Callable[[ProcessInfo], Awaitable[None]] | None = None,
        *,
        plan: Plan | None = None,
        then: str | None = None,
    ) -> ProcessInfo:
        """Start a process for ``task`` holding ``devices`` (plus the always-attached ones).

        ``plan`` is the offline engine's plan, ``then`` an LLM kernel's follow-up: both ride on the
        job and come back on its callback. ``before_start(info)`` runs once the leases are granted and before any worker has the job
        (the kernel records the launch durably there); if it fails, nothing is started.
        Returns as soon as a worker has the job, or the job waits in the pool's queue because
        ``max_workers`` processes run already (it starts, in order, when one ends). Raises
        :class:`LaunchRefused` when the task is
        empty, a device is unknown, unavailable, or held exclusively by another process.
        """
        task = task.strip()
        if self.emergency_stop is not None:
            raise LaunchRefused(
                f"emergency stop is latched ({self.emergency_stop.reason}); nothing may run until a person "
                "resets it with `rosaos estop --reset` or the web page"
            )
        if not task:
            raise LaunchRefused("the task is empty; describe what the process should do")
        endpoints = await self._started(devices)
        process_id = self._next_id
        try:
            granted = self.leases.acquire(process_id, task, devices, endpoints)
        except LeaseRefused as refusal:
            raise LaunchRefused(str(refusal)) from None
        self._next_id += 1
        job = WorkerJob(
            process_id=process_id,
            task=task,
            plan=plan,
            then=then,
            devices=[_granted(endpoints[name], asked=name in devices) for name in granted],
            model=self._model,
            base_prompt=self._base_prompt,
            timeout=self._job_timeout,
            request_limit=self._request_limit,
            kernel_url=self._kernel_url,
            kernel_token=self._kernel_token,
            world_devices=sorted(endpoints),
        )
        info = ProcessInfo(
            id=process_id,
            task=task,
            devices=granted,
            state="running",
            started_at=_now(),
            then=plan.then.summary if plan is not None and plan.then is not None else then,
            plan=plan,
        )
        self._processes[process_id] = info
        if before_start is not None:
            try:
                await before_start(info.model_copy())
            except LaunchRefused:
                self._end(process_id, "error")
                raise
            except Exception as failure:
                self._end(process_id, "error")
                raise LaunchRefused(
                    f"could not record the launch, so it was not started: {failure}"
                ) from None
        try:
            if self.warming is not None and not self.warming.done():
                await asyncio.shield(self.warming)  # in launch order: waiters wake first come, first served
            handle = await self._pool.run(job)
        except (PoolError, ValueError) as failure:
            self._end(process_id, "error")
            raise LaunchRefused(f"could not start a worker for the process: {failure}") from None
        info.worker_pid = handle.worker_pid
        if info.state == "terminated":
            # terminate() (or stop()) came while a one-off worker was being spawned: honour it now.
            await self._pool.terminate(process_id)
        return info.model_copy()

    async def _started(self, devices: builtins.list[str]) -> Mapping[str, DeviceEndpoint]:
        """The endpoints, once ``devices`` still starting (``rosaos up`` shows its banner before
        every device is up) are up, or after ``starting_wait`` s: a command right after the banner
        waits for its lamp instead of being refused. A device known to be down is not waited for."""
        endpoints = self._devices()
        starting = [
            name
            for name in devices
            if (endpoint := endpoints.get(name)) is not None
            and endpoint.status == "starting"
            and not endpoint.url
        ]
        if not starting or self._starting is None:
            return endpoints
        log.info("waiting up to %g s for %s to start", self.starting_wait, ", ".join(starting))
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(self.starting_wait):
                await self._starting(starting)
        return self._devices()

    async def terminate(self, process_id: int) -> ProcessInfo:
        """Kill a running process and release its leases; an ended process is returned as it is.

        Raises ``KeyError`` with a readable message for an id that was never launched.
        """
        info = self._get(process_id)
        if info.state == "running" and not await self._pool.terminate(process_id):
            # No worker has the job: launch() is still spawning one, and will kill it on return.
            self._end(process_id, "terminated")
        return self._get(process_id).model_copy()

    def list(self, include_ended: bool = False) -> builtins.list[ProcessInfo]:
        """The running processes (and the ended ones too with ``include_ended``), oldest first."""
        return [
            info.model_copy()
            for info in sorted(self._processes.values(), key=lambda info: info.id)
            if include_ended or info.state == "running"
        ]

    def get(self, process_id: int) -> ProcessInfo:
        """One process by id; ``KeyError`` with a readable message for an unknown id."""
        return self._get(process_id).model_copy()

    def record_progress(self, progress: Progress) -> None:
        """Keep a running process's latest progress (from its worker); others are ignored."""
        info = self._processes.get(progress.process_id)
        if info is None or info.state != "running":
            return
        info.progress = ProcessProgress(
            device=progress.device,
            progress=progress.progress,
            total=progress.total,
            message=progress.message,
            at=datetime.now(UTC),
        )

    def _worker_started(self, process_id: int, worker_pid: int) -> None:
        """A queued process got its worker (the pool had ``max_workers`` running when it launched)."""
        info = self._processes.get(process_id)
        if info is not None:
            info.worker_pid = worker_pid

    def record_callback(self, callback: WorkerCallback) -> None:
        """Mark the process ended as ``callback`` says and release its leases. Idempotent.

        Called for every end the pool reports, and by the kernel for an orphan's end after a
        restart. A callback for a process this manager does not know is ignored.
        """
        self._end(callback.process_id, callback.status)

    def remember(self, info: ProcessInfo) -> None:
        """List a process a dead kernel left (``ps --all`` shows it); it holds no lease here.

        Its end comes next, through :meth:`record_callback`, from the kernel's orphan recovery."""
        self._processes.setdefault(info.id, info.model_copy())

    async def _worker_ended(self, callback: WorkerCallback) -> None:
        self.record_callback(callback)
        await self._on_ended(callback)

    def _end(self, process_id: int, state: ProcessState) -> None:
        info = self._processes.get(process_id)
        if info is None:
            return
        if info.state == "running":
            info.state, info.ended_at = state, _now()
        self.leases.release(process_id)

    def _get(self, process_id: int) -> ProcessInfo:
        try:
            return self._processes[process_id]
        except KeyError:
            running = ", ".join(str(pid) for pid, info in self._processes.items() if info.state == "running")
            raise KeyError(
                f"no process {process_id}; running processes: {running or 'none'} (see list_processes)"
            ) from None


def _granted(endpoint: DeviceEndpoint, asked: bool = True) -> GrantedDevice:
    """The job's view of a granted device. One granted only because it is always attached (the
    kernel did not ask for it) comes with its speaking tools and short prompt, if its driver has them:
    a light switch need not carry the Reachy's head, camera and emotions."""
    assert endpoint.url is not None, "the lease table grants served devices only"
    attached_only = not asked and endpoint.always_attached and bool(endpoint.attached_tools)
    return GrantedDevice(
        name=endpoint.name,
        driver=endpoint.driver,
        url=endpoint.url,
        token=endpoint.token,
        description=endpoint.description,
        prompt=(endpoint.attached_prompt or endpoint.prompt) if attached_only else endpoint.prompt,
        confirm=endpoint.confirm,
        tools=list(endpoint.attached_tools) if attached_only else None,
        on_request_tools=list(endpoint.on_request_tools),
        on_request_pattern=endpoint.on_request_pattern,
        server_epoch=endpoint.server_epoch,
    )


def _now() -> datetime:
    return datetime.now(UTC)
