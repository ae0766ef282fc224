"""The worker watcher: what the pool knows about each worker process, and the task that watches it.

Each worker runs in its own process group and is watched by one task that reads its typed
messages (:mod:`rosaos.processes.protocol`) and notices when it exits. That watcher is the only
place a job's end is reported, so each job is reported exactly once, to the pool's ``on_ended``:

- ``done`` message: the worker's own callback.
- the process exits mid-job: ``crashed`` (with its exit code or signal), unless the pool killed
  it on purpose: ``timeout`` (the job overran ``timeout + kill_grace``) or ``terminated``.

Whichever comes first takes the job off the worker (``worker.job`` back to None), so the other
finds nothing left to report. Killing (:meth:`Worker.kill`) means SIGKILL to the whole process
group; the watcher then waits for the exit, so nothing the worker started outlives it.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
from collections.abc import Awaitable, Callable
from typing import Any, Protocol

from pydantic import ValidationError

from rosaos.events.callback import ProcessStatus, WorkerCallback
from rosaos.processes.jobs import WorkerJob
from rosaos.processes.protocol import WORKER_MESSAGE, Done, Progress, Ready, Rejected

log = logging.getLogger(__name__)

OnEnded = Callable[[WorkerCallback], Awaitable[None]]
"""Called once per job with the callback that says how it ended."""

RETIRE_GRACE = 5.0
"""Seconds a worker that closed its stdout (retired, or broken) gets to exit before it is killed."""


class WorkerProcess(Protocol):
    """What the pool uses of a worker process: ``asyncio.subprocess.Process``, or a forked worker."""

    @property
    def pid(self) -> int: ...

    @property
    def stdin(self) -> asyncio.StreamWriter | None: ...

    @property
    def stdout(self) -> asyncio.StreamReader | None: ...

    @property
    def returncode(self) -> int | None: ...

    async def wait(self) -> int: ...


class Worker:
    """One worker subprocess and what the pool knows about it."""

    def __init__(self, proc: WorkerProcess, one_off: bool) -> None:
        self.proc = proc
        self.one_off = one_off
        self.ready = asyncio.Event()
        self.ready_seen = False
        """True once the worker said ``ready`` (``ready`` is also set when it dies, to wake waiters)."""
        self.exited = asyncio.Event()
        """Set once the exit has been handled: the job reported, a replacement requested."""
        self.job: WorkerJob | None = None
        self.kill_reason: ProcessStatus | None = None
        self.deadline: asyncio.TimerHandle | None = None

    @property
    def pid(self) -> int:
        return self.proc.pid

    def kill(self, reason: ProcessStatus) -> None:
        """SIGKILL the worker's process group; its job is then reported as ``reason``."""
        if self.exited.is_set():
            return
        if self.kill_reason is None:
            self.kill_reason = reason
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.pid, signal.SIGKILL)

    def cancel_deadline(self) -> None:
        """Drop the timer that would kill the worker for running past its job's timeout."""
        if self.deadline is not None:
            self.deadline.cancel()
            self.deadline = None

    def retire(self) -> None:
        """Let a one-off worker exit on its own (stdin closed); kill it if it lingers."""
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        asyncio.get_running_loop().call_later(RETIRE_GRACE, self.kill, "terminated")


class Watcher:
    """Watches a pool's workers, one task each until the worker exits, and reports their jobs' ends.

    ``report`` delivers a job's end (the pool passes it on to its ``on_ended``). The pool is
    also told what it must act on: ``ready`` when a worker finished its imports, ``gone`` once
    an exited worker is reaped (before its job is reported), and ``exited`` after that report.
    """

    def __init__(
        self,
        report: OnEnded,
        *,
        ready: Callable[[Worker], None],
        gone: Callable[[Worker], None],
        exited: Callable[[Worker, int], None],
        progress: Callable[[Progress], None] | None = None,
    ) -> None:
        self._report = report
        self._progress = progress
        self._ready = ready
        self._gone = gone
        self._exited = exited
        self._tasks: set[asyncio.Task[Any]] = set()

    def watch(self, worker: Worker) -> None:
        """Start the task that watches ``worker`` until it exits."""
        task = asyncio.create_task(self._watch(worker), name=f"rosaos-worker-{worker.pid}")
        # Referenced so the watcher is not garbage-collected while it runs.
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def _watch(self, worker: Worker) -> None:
        """Read the worker's protocol lines until it exits, then report its job (the pool replaces it)."""
        assert worker.proc.stdout is not None
        try:
            while line := await worker.proc.stdout.readline():
                await self._on_line(worker, line)
        except (ValueError, asyncio.LimitOverrunError) as failure:
            log.error("worker %d broke the protocol (%s); killing it", worker.pid, failure)
            worker.kill("crashed")
        finally:
            await self._on_exit(worker)

    async def _on_exit(self, worker: Worker) -> None:
        try:
            returncode = await asyncio.wait_for(worker.proc.wait(), timeout=RETIRE_GRACE)
        except TimeoutError:  # stdout closed but the process lives on: it is of no use any more
            worker.kill("crashed")
            returncode = await worker.proc.wait()
        # SIGKILL the group also when the leader exited alone: nothing it started may linger.
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(worker.pid, signal.SIGKILL)
        self._gone(worker)
        worker.ready.set()  # wake start() if the worker died while importing
        job, worker.job = worker.job, None
        try:
            if job is not None:
                worker.cancel_deadline()
                await self._report_killed(worker, job, returncode)
        finally:
            self._exited(worker, returncode)
            worker.exited.set()

    async def _on_line(self, worker: Worker, line: bytes) -> None:
        try:
            message = WORKER_MESSAGE.validate_json(line)
        except ValidationError as invalid:  # a stray line, or a worker from another rosaOS version
            await self._on_invalid(worker, line, invalid)
            return
        if isinstance(message, Ready):
            worker.ready_seen = True
            worker.ready.set()
            self._ready(worker)
        elif isinstance(message, Done):
            await self._on_done(worker, message)
        elif isinstance(message, Progress):
            job = worker.job
            if self._progress is not None and job is not None and message.process_id == job.process_id:
                self._progress(message)
        elif isinstance(message, Rejected) and worker.job is not None:
            job, worker.job = worker.job, None
            worker.cancel_deadline()
            await self._report(ended(job, "error", f"the worker rejected the job: {message.error}"))

    async def _on_done(self, worker: Worker, done: Done) -> None:
        job = worker.job
        if job is None or done.process_id != job.process_id or done.callback.process_id != job.process_id:
            log.warning("worker %d reported an unexpected job end: %s", worker.pid, done)
            return
        worker.job = None
        worker.cancel_deadline()
        if worker.one_off:
            worker.retire()
        await self._report(done.callback)

    async def _on_invalid(self, worker: Worker, line: bytes, invalid: ValidationError) -> None:
        """A line that is no protocol message is logged; one that meant to end the job ends it as an error."""
        log.warning("worker %d wrote a line that is not a protocol message: %r", worker.pid, line[:200])
        job = worker.job
        if job is None or not line.lstrip().startswith(b'{"event":"done"'):
            return
        worker.job = None
        worker.cancel_deadline()
        if worker.one_off:
            worker.retire()
        await self._report(ended(job, "error", f"the worker sent an invalid end of the process: {invalid}"))

    async def _report_killed(self, worker: Worker, job: WorkerJob, returncode: int) -> None:
        if worker.kill_reason == "timeout":
            status: ProcessStatus = "timeout"
            error = f"the process ran past its timeout of {job.timeout:g} s and its worker was killed"
        elif worker.kill_reason == "terminated":
            status, error = "terminated", "the process was terminated on request"
        else:
            status = "crashed"
            error = (
                f"the worker process (pid {worker.pid}) died while running the task "
                f"({describe_exit(returncode)}); the task may be half done, so check the "
                "devices' state before retrying"
            )
        await self._report(ended(job, status, error))


def describe_exit(returncode: int) -> str:
    """``exit code 1``, or ``killed by SIGKILL`` for a negative ``returncode``."""
    if returncode < 0:
        try:
            return f"killed by {signal.Signals(-returncode).name}"
        except ValueError:
            return f"killed by signal {-returncode}"
    return f"exit code {returncode}"


def ended(job: WorkerJob, status: ProcessStatus, error: str) -> WorkerCallback:
    return WorkerCallback(
        process_id=job.process_id, status=status, error=error, task=job.task, plan=job.plan, then=job.then
    )
