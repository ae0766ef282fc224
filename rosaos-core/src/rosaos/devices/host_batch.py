"""Several device instances in one host process: what ``rosaos up`` does with simulators.

A simulated Tapo bulb needs a few MB; a Python interpreter with FastMCP, uvicorn and pydantic
needs about 75. So the supervisor hands one host process a :class:`HostBatch` of instances, and
the host serves each on its own port, side by side on one event loop. Each instance keeps its own
URL, backend and ``safe_stop``; what they share is the process, so a crash of that process
restarts them together (and only them), and the supervisor reports each one going down and back.

The handshake is one JSON line per instance, each naming it: ``{"instance", "url", "pid"}`` when
it serves, or ``{"instance", "error"}`` when it could not start. An instance that cannot start
does not stop the others; the supervisor retries it in a process of its own. An instance whose
server stops after it was ready ends the whole process with code 1, so the supervisor notices at
once and restarts the batch.

An instance whose driver starts in the background (``DriverSpec.background_start``: the Reachy
simulator, whose MuJoCo daemon boots for seconds) joins a running host later: the supervisor
writes its :class:`HostJob` as one more line on the host's stdin, once the others are up and
``rosaos up`` has said so, and the host answers with that instance's line. So the daemon's boot
holds up neither the banner nor the other instances, and one interpreter serves them all (a
second host for the Reachy alone cost about 120 MiB PSS). The daemon itself, the native and
heavy part, stays a child process of its own (``rosaos_reachy.daemon``).

At most :data:`STARTING_AT_ONCE` instances start at the same time. Started all together, a
hundred instances share the CPU fairly and each takes a hundred times longer, so on a busy
machine every one of them overruns its driver's own start-up timeout (a Tapo simulator allows
5 s); a few at a time, each starts quickly and the last is ready no later.
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
import sys
from collections.abc import Callable
from typing import Any, TextIO

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from rosaos.devices.heartbeat import beat
from rosaos.devices.host import HostJob, install_stop_signals, serve_until_stopped
from rosaos.devices.serve import ServedDevice
from rosaos.drivers import DeviceError

log = logging.getLogger("rosaos.devices.host")

STARTING_AT_ONCE = 8


class HostBatch(BaseModel):
    """What one host process serves when it serves several instances."""

    model_config = ConfigDict(extra="forbid")

    jobs: list[HostJob] = Field(min_length=1)


class BatchHandshake:
    """One line per instance on the host's stdout; each instance speaks once."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.sent: set[str] = set()

    def send(self, instance: str, message: dict[str, Any]) -> None:
        """Write the instance's line once; anything later goes to the log only."""
        if instance in self.sent:
            log.error("%s: %s", instance, message.get("error", message))
            return
        self.sent.add(instance)
        self.stream.write(json.dumps({"instance": instance, **message}) + "\n")
        self.stream.flush()


async def read_joining_jobs(stop: asyncio.Event, join: Callable[[HostJob], None]) -> None:
    """Read the supervisor's later jobs from stdin, one JSON line each, until EOF, which sets ``stop``.

    EOF means the supervisor is gone or let go: no orphan host lingers. A line that is not a job is
    logged and skipped (the supervisor's wait for that instance then times out and says so).
    """
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader()
    try:
        await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), sys.stdin)
    except (ValueError, OSError):  # not a pipe (a terminal or a file): nobody to watch
        return
    while line := await reader.readline():
        if not line.strip():
            continue
        try:
            join(HostJob.model_validate_json(line))
        except ValidationError as error:
            log.error("ignoring a job line the host cannot read: %s", error)
    stop.set()


async def run_batch(batch: HostBatch, handshake: BatchHandshake, watch_stdin: bool) -> int:
    """Serve every job of ``batch``, and those that join later, until stopped; 1 when one of them
    broke after it was ready."""
    stop = asyncio.Event()
    install_stop_signals(stop)
    joined: set[asyncio.Task[None]] = set()

    def join(job: HostJob) -> None:
        if stop.is_set():
            return
        task = asyncio.create_task(serve(job), name=f"serve {job.instance}")
        joined.add(task)

    watcher = asyncio.create_task(read_joining_jobs(stop, join)) if watch_stdin else None
    heartbeat = batch.jobs[0].heartbeat
    ticker = asyncio.create_task(beat(handshake.stream, heartbeat)) if watch_stdin else None
    broke: list[str] = []
    starting = asyncio.Semaphore(STARTING_AT_ONCE)

    async def serve(job: HostJob) -> None:
        await starting.acquire()
        turn = [True]  # this instance holds a start-up turn until it is ready or has failed

        def give_back() -> None:
            if turn:
                turn.clear()
                starting.release()

        def ready(served: ServedDevice) -> None:
            give_back()
            handshake.send(job.instance, {"url": served.url, "pid": os.getpid()})
            log.info("%s (%s, %s) serving at %s", job.instance, job.driver, job.backend, served.url)

        try:
            token = job.token_file.read_text(encoding="utf-8").strip()
            if not token:
                raise DeviceError(f"token file {job.token_file} is empty")
            await serve_until_stopped(
                job.resolve(), job.data_dir, token, job.host, job.port, ready, stop, job.preferred_port
            )
        except Exception as error:  # one instance's trouble is reported; the others keep serving
            if job.instance in handshake.sent:
                log.exception(
                    "%s stopped serving; the host exits so the supervisor restarts it", job.instance
                )
                broke.append(job.instance)
                stop.set()
                return
            if not isinstance(error, DeviceError | OSError):
                log.exception("%s could not start", job.instance)
            reason = (
                str(error) if isinstance(error, DeviceError | OSError) else f"{type(error).__name__}: {error}"
            )
            handshake.send(job.instance, {"error": reason})
        finally:
            give_back()

    try:
        await asyncio.gather(*(serve(job) for job in batch.jobs))
        # The first jobs end when the host stops (or none could start); the joined ones then too.
        if joined:
            stop.set()
            await asyncio.gather(*joined)
    finally:
        for task in (watcher, ticker):
            if task is not None:
                task.cancel()
    return 1 if broke or not handshake.sent else 0
