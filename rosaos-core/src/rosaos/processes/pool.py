"""The warm worker pool: long-lived worker subprocesses that run process agents, one job each at a time.

Importing pydantic-ai and FastMCP takes seconds, so workers are started ahead of time and reused.
When every warm worker is busy, a one-off worker is spawned for the job and retired after it.
At most ``max_workers`` jobs run at once (default sized to the machine,
:mod:`rosaos.processes.capacity`); a job beyond that waits in the pool's queue, in order, and
starts when a running one ends. Nothing is refused for being one too many.
Warm and one-off workers alike are forked by the fork server (:mod:`rosaos.processes.forking`),
which did those imports once, so a worker starts in milliseconds and shares the server's memory;
when the fork server is off or not available, a worker is started as a new Python process.
Either way the pool handles it the same.

This module holds the pool's public API and its scheduling: which worker gets a job, when a job
overruns, how workers are started and replaced. Each worker runs in its own process group and is
watched by one task, in :mod:`rosaos.processes.watcher`: the only place a job's end is reported
(``done``, ``crashed``, ``timeout`` or ``terminated``), so each job is reported exactly once, to
``on_ended``.

Killing means SIGKILL to the whole process group, then waiting for the exit, so no worker (or
anything it started) outlives a terminate, a timeout or :meth:`WorkerPool.stop`. A warm worker
that dies is replaced, so the pool keeps its size.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
import sys
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from rosaos.events.callback import WorkerCallback
from rosaos.processes.capacity import default_max_workers
from rosaos.processes.forking import ForkServer, ForkServerError
from rosaos.processes.jobs import WorkerJob
from rosaos.processes.protocol import Progress
from rosaos.processes.watcher import OnEnded, Watcher, Worker, WorkerProcess, describe_exit, ended

log = logging.getLogger(__name__)

LINE_LIMIT = 16 * 1024 * 1024
MAX_RESTART_DELAY = 30.0
"""Longest wait before replacing a worker, when workers keep dying during start-up."""


class PoolError(Exception):
    """The pool cannot run workers; the message says what to check."""


@dataclass(frozen=True)
class JobHandle:
    """Where a job runs."""

    process_id: int
    worker_pid: int | None
    """None while the job waits in the queue for a free worker."""
    one_off: bool
    queued: int = 0
    """Jobs ahead of this one in the queue, plus one; 0 when it runs at once."""


@dataclass(frozen=True)
class WorkerStats:
    """One worker, for ``rosaos ps`` and the benchmarks."""

    pid: int
    state: Literal["starting", "idle", "busy"]
    one_off: bool
    process_id: int | None
    rss_bytes: int | None


class WorkerPool:
    """A warm pool of ``size`` worker subprocesses running ``python -m rosaos.processes.worker``.

    ``env`` is added to this process's environment for the workers (e.g. ``PYTHONPATH``).
    A job may run ``kill_grace`` seconds past its timeout (the worker stops it itself at the
    timeout and reports it) before the pool kills the worker. With ``fork_server``, one-off
    workers are forked by a fork server that imports ``preload`` modules ahead, besides the
    worker's own. With ``park`` (a name per data directory) the fork server outlives a kernel that
    dies, for a minute, and the next kernel adopts it (:mod:`rosaos.processes.fork_parking`).
    """

    def __init__(
        self,
        size: int = 2,
        python: str = sys.executable,
        env: Mapping[str, str] | None = None,
        *,
        on_ended: OnEnded | None = None,
        kill_grace: float = 5.0,
        start_timeout: float = 60.0,
        fork_server: bool = True,
        preload: Sequence[str] = (),
        max_workers: int | None = None,
        park: str | None = None,
    ) -> None:
        if size < 0:
            raise ValueError("pool size must be 0 or more")
        self.size = size
        self.max_workers = max(1, size, max_workers or default_max_workers())
        """Jobs that may run at once; more wait in the queue (see the module docstring)."""
        self.python = python
        self.on_ended = on_ended
        """Where job ends are reported; the process manager sets it."""
        self.on_progress: Callable[[Progress], None] | None = None
        """Where a running job's progress messages go; the manager sets it."""
        self.on_started: Callable[[int, int], None] | None = None
        """Called as (process id, worker pid) when a queued job gets its worker."""
        self.kill_grace = kill_grace
        self.start_timeout = start_timeout
        self._env = {**os.environ, **(env or {})}
        self.preload = list(preload)
        """Modules the fork server imports ahead (the process manager adds its model's)."""
        self.fork_server = ForkServer(python, self._env, park=park) if fork_server else None
        self._workers: set[Worker] = set()
        self._spawning: set[asyncio.Task[Any]] = set()
        self._watcher = Watcher(
            self._report,
            ready=self._worker_ready,
            gone=self._workers.discard,
            exited=self._worker_exited,
            progress=self._progress,
        )
        self._stopping = False
        self._start_failures = 0
        self._queue: deque[WorkerJob] = deque()
        self._running: set[int] = set()
        """Process ids holding a slot: on a worker, or having one started for them."""
        self._cancelled: set[int] = set()
        """Terminated while a worker was being started for them: killed once it is there."""

    async def start(self) -> None:
        """Start the warm workers and the fork server; wait until they have finished their imports.

        A fork server that fails to start is logged, not raised: one-offs then start the slow way.
        """
        self._stopping = False
        if self.fork_server is not None:
            # The warm workers are forked from it too: one process pays the imports, the workers
            # share its pages, and on a small machine three interpreters no longer import at once.
            self.fork_server.preload = self.preload
            self.fork_server.start()
            with contextlib.suppress(TimeoutError):
                async with asyncio.timeout(self.start_timeout):
                    await self.fork_server.wait_ready()
        try:
            workers = [await self._spawn(one_off=False) for _ in range(self.size)]
        except PoolError:
            await self.stop()
            raise
        hint = f"run 'echo | {self.python} -m rosaos.processes.worker' to see why"
        try:
            async with asyncio.timeout(self.start_timeout):
                await asyncio.gather(*(worker.ready.wait() for worker in workers))
        except TimeoutError:
            await self.stop()
            raise PoolError(f"workers did not start within {self.start_timeout:g} s; {hint}") from None
        codes = [str(worker.proc.returncode) for worker in workers if worker.proc.returncode is not None]
        if codes:
            await self.stop()
            raise PoolError(f"worker exited during start-up (exit code {', '.join(codes)}); {hint}")
        fork_server = self.fork_server
        if fork_server is not None and not fork_server.ready and fork_server.unusable is None:
            log.warning("the fork server is not ready; workers start the slow way until it is")

    async def run(self, job: WorkerJob) -> JobHandle:
        """Give ``job`` to an idle warm worker, or a new one-off worker if all are busy; or queue it
        when ``max_workers`` jobs run already (the handle then has no worker pid)."""
        if self._stopping:
            raise PoolError("the worker pool is stopped")
        if job.process_id in self._running or any(q.process_id == job.process_id for q in self._queue):
            raise ValueError(f"process {job.process_id} is already running")
        if self._queue or len(self._running) >= self.max_workers:
            self._queue.append(job)
            log.info("process %d waits for a worker (%d queued)", job.process_id, len(self._queue))
            return JobHandle(job.process_id, None, False, queued=len(self._queue))
        return await self._start_job(job)

    async def _start_job(self, job: WorkerJob) -> JobHandle:
        self._running.add(job.process_id)
        try:
            idle = [worker for worker in self._workers if self._is_idle(worker)]
            # A warm worker that is still importing is still faster than a fresh one-off.
            idle.sort(key=lambda worker: not worker.ready.is_set())
            if idle:
                worker = idle[0]
                self._assign(worker, job)
            else:
                worker = await self._spawn(one_off=True, job=job)
        except BaseException:
            self._running.discard(job.process_id)
            raise
        await self._send(worker, job)
        if job.process_id in self._cancelled:
            worker.kill("terminated")
        return JobHandle(job.process_id, worker.pid, worker.one_off)

    def queued(self) -> int:
        """Jobs waiting for a worker."""
        return len(self._queue)

    def _dispatch(self) -> None:
        """Start queued jobs, oldest first, while there is room."""
        while self._queue and len(self._running) < self.max_workers and not self._stopping:
            job = self._queue.popleft()
            self._running.add(job.process_id)  # counted now, so the loop does not overfill
            task = asyncio.create_task(self._start_queued(job))
            self._spawning.add(task)
            task.add_done_callback(self._spawning.discard)

    async def _start_queued(self, job: WorkerJob) -> None:
        try:
            handle = await self._start_job(job)
        except PoolError as failure:
            self._running.discard(job.process_id)
            await self._report(ended(job, "error", f"could not start a worker for the process: {failure}"))
            return
        if self.on_started is not None and handle.worker_pid is not None:
            self.on_started(job.process_id, handle.worker_pid)

    def _progress(self, progress: Progress) -> None:
        if self.on_progress is not None:
            self.on_progress(progress)

    async def terminate(self, process_id: int) -> bool:
        """Kill the worker running ``process_id`` and wait until its end is reported.

        Returns False when no worker is running that process (it already ended).
        """
        for job in self._queue:
            if job.process_id == process_id:
                self._queue.remove(job)
                await self._report(ended(job, "terminated", "the process was terminated on request"))
                return True
        worker = self._worker_for(process_id)
        if worker is None:
            if process_id in self._running:  # its worker is being started: kill it once it is there
                self._cancelled.add(process_id)
            return False
        worker.kill("terminated")
        await worker.exited.wait()
        return True

    async def stop(self) -> None:
        """Kill every worker (jobs still running are reported ``terminated``) and wait for them."""
        self._stopping = True
        while self._queue:
            job = self._queue.popleft()
            await self._report(ended(job, "terminated", "rosaOS stopped before the process started"))
        for task in list(self._spawning):
            task.cancel()
        await asyncio.gather(*self._spawning, return_exceptions=True)
        workers = list(self._workers)
        for worker in workers:
            worker.kill("terminated")
        await asyncio.gather(*(worker.exited.wait() for worker in workers))
        if self.fork_server is not None:
            await self.fork_server.stop()

    def stats(self) -> list[WorkerStats]:
        """Every live worker: pid, state, job and resident memory (read from /proc on Linux)."""
        rows = []
        for worker in sorted(self._workers, key=lambda worker: worker.pid):
            state: Literal["starting", "idle", "busy"]
            if worker.job is not None:
                state = "busy"
            elif worker.ready.is_set():
                state = "idle"
            else:
                state = "starting"
            process_id = worker.job.process_id if worker.job else None
            rows.append(WorkerStats(worker.pid, state, worker.one_off, process_id, _rss_bytes(worker.pid)))
        return rows

    async def wait_until_warm(self) -> None:
        """Wait until the pool has ``size`` warm workers that finished their imports."""
        while True:
            warm = [worker for worker in self._workers if not worker.one_off and worker.ready.is_set()]
            if len(warm) >= self.size and not self._spawning:
                return
            await asyncio.sleep(0.05)

    # -- workers ------------------------------------------------------------------------------

    async def _spawn(self, one_off: bool, job: WorkerJob | None = None) -> Worker:
        proc = await self._fork()
        if proc is None:
            if self._stopping:
                raise PoolError("the worker pool is stopped")
            proc = await self._exec()
        if self._stopping:  # stop() ran while this worker was being started: it must not outlive it
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
            await proc.wait()
            raise PoolError("the worker pool is stopped")
        worker = Worker(proc, one_off)
        # No await between registering and assigning: no other run() can take this worker.
        self._workers.add(worker)
        if job is not None:
            self._assign(worker, job)
        self._watcher.watch(worker)
        log.debug("started %s worker %d", "one-off" if one_off else "warm", proc.pid)
        return worker

    async def _fork(self) -> WorkerProcess | None:
        """A worker from the fork server; None when it cannot give one (then spawn one)."""
        if self.fork_server is None or not self.fork_server.ready or self._stopping:
            return None
        try:
            return await self.fork_server.spawn(LINE_LIMIT)
        except ForkServerError as failure:
            log.warning("the fork server could not start a worker (%s); spawning one instead", failure)
        except Exception:
            log.exception("the fork server could not start a worker; spawning one instead")
        return None

    async def _exec(self) -> WorkerProcess:
        """A new ``python -m rosaos.processes.worker`` process."""
        try:
            return await asyncio.create_subprocess_exec(
                self.python,
                "-P",  # the working directory must not shadow a module (a stray h2.py)
                "-m",
                "rosaos.processes.worker",
                stdin=asyncio.subprocess.PIPE,
                stdout=asyncio.subprocess.PIPE,
                env=self._env,
                # Own process group: a kill takes everything the worker started with it, and a
                # Ctrl-C in the terminal reaches the kernel, which then stops the pool in order.
                start_new_session=True,
                limit=LINE_LIMIT,
            )
        except OSError as failure:
            raise PoolError(f"cannot start a worker with {self.python}: {failure.strerror}") from None

    def _replace(self, delay: float) -> None:
        async def replace() -> None:
            await asyncio.sleep(delay)
            try:
                await self._spawn(one_off=False)
            except PoolError as failure:
                log.error("could not replace a worker: %s", failure)

        task = asyncio.create_task(replace())
        self._spawning.add(task)
        task.add_done_callback(self._spawning.discard)

    def _assign(self, worker: Worker, job: WorkerJob) -> None:
        worker.job = job
        deadline = job.timeout + self.kill_grace
        worker.deadline = asyncio.get_running_loop().call_later(deadline, worker.kill, "timeout")

    async def _send(self, worker: Worker, job: WorkerJob) -> None:
        assert worker.proc.stdin is not None
        # A worker that died already is reported by its watcher; the write error adds nothing.
        with contextlib.suppress(ConnectionError, RuntimeError):
            worker.proc.stdin.write(job.model_dump_json().encode() + b"\n")
            await worker.proc.stdin.drain()

    def _is_idle(self, worker: Worker) -> bool:
        return (
            worker.job is None
            and not worker.one_off
            and worker.kill_reason is None
            and worker.proc.returncode is None
        )

    def _worker_for(self, process_id: int) -> Worker | None:
        for worker in self._workers:
            if worker.job is not None and worker.job.process_id == process_id:
                return worker
        return None

    # -- what the watcher tells the pool ------------------------------------------------------

    def _worker_ready(self, worker: Worker) -> None:
        """A worker finished its imports: start-up works again, so the back-off starts over."""
        self._start_failures = 0

    def _worker_exited(self, worker: Worker, returncode: int) -> None:
        """The worker's exit is handled and its job reported: replace it if it was a warm one."""
        if not worker.one_off and not self._stopping:
            self._replace(self._replacement_delay(worker, returncode))

    def _replacement_delay(self, worker: Worker, returncode: int) -> float:
        """No delay, unless workers keep dying during start-up: then back off instead of looping."""
        if worker.ready_seen or worker.kill_reason is not None:
            return 0.0
        self._start_failures += 1
        delay = min(MAX_RESTART_DELAY, 0.5 * 2**self._start_failures)
        log.error(
            "worker %d exited during start-up (%s); next try in %g s. Run "
            "'echo | %s -m rosaos.processes.worker' to see why",
            worker.pid,
            describe_exit(returncode),
            delay,
            self.python,
        )
        return delay

    async def _report(self, callback: WorkerCallback) -> None:
        """Pass a job's end on to ``on_ended`` (the watcher calls this once per job); start the next."""
        self._running.discard(callback.process_id)
        self._cancelled.discard(callback.process_id)
        self._dispatch()
        if self.on_ended is None:
            log.info("process %d ended: %s", callback.process_id, callback.status)
            return
        try:
            await self.on_ended(callback)
        except Exception:
            log.exception("on_ended failed for process %d", callback.process_id)


def _rss_bytes(pid: int) -> int | None:
    # /proc is in memory, so this read does not block the event loop in any meaningful way.
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None
