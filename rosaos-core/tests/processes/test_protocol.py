"""The worker's pipe protocol: typed messages, and a job's end reported once, whatever the worker writes.

The watcher tests run a real child process that writes chosen lines to its stdout, as a worker
from another rosaOS version, or a broken one, might.
"""

from __future__ import annotations

import asyncio
import os
import signal
import sys

import pytest
from pydantic import ValidationError

from rosaos.processes.jobs import WorkerCallback
from rosaos.processes.protocol import WORKER_MESSAGE, Done, Progress, encode
from rosaos.processes.watcher import Watcher, Worker

from .processes_support import Endings, KernelStandIn, make_job

STAND_IN = KernelStandIn(url="http://127.0.0.1:9")


def test_a_done_message_carries_the_callback_through_one_line() -> None:
    callback = WorkerCallback(process_id=3, status="ok", output="lamp on", task="turn on the lamp")
    line = encode(Done(process_id=3, callback=callback))
    assert line.endswith("\n") and line.count("\n") == 1
    assert WORKER_MESSAGE.validate_json(line) == Done(process_id=3, callback=callback)


def test_progress_is_told_apart_by_its_event_field() -> None:
    message = WORKER_MESSAGE.validate_json(
        '{"event": "progress", "process_id": 2, "device": "winch", "progress": 3, "total": 10}'
    )
    assert message == Progress(process_id=2, device="winch", progress=3, total=10)


@pytest.mark.parametrize(
    "line",
    [
        '{"event": "finished", "process_id": 1}',  # no such message
        '{"event": "done", "process_id": 1, "delivered": true, "callback": {"process_id": 1, "status": "ok"}}',
    ],
)
def test_a_message_that_is_not_in_the_protocol_is_refused(line: str) -> None:
    """The second line is the old ``done`` with ``delivered``: the HTTP route it spoke of is gone."""
    with pytest.raises(ValidationError):
        WORKER_MESSAGE.validate_json(line)


async def writer(*lines: str) -> asyncio.subprocess.Process:
    """A child that writes ``lines`` to stdout, then waits for stdin to close (as a worker does)."""
    script = "import sys\nfor line in sys.argv[1:]:\n    print(line, flush=True)\nsys.stdin.read()\n"
    return await asyncio.create_subprocess_exec(
        sys.executable,
        "-c",
        script,
        *lines,
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
        start_new_session=True,
    )


async def watch(proc: asyncio.subprocess.Process, endings: Endings, process_id: int) -> Worker:
    worker = Worker(proc, one_off=False)
    worker.job = make_job(STAND_IN, "unused", process_id=process_id)
    Watcher(endings.record, ready=lambda w: None, gone=lambda w: None, exited=lambda w, c: None).watch(worker)
    return worker


async def test_a_stray_line_is_ignored_and_the_done_message_ends_the_job_once() -> None:
    endings = Endings()
    callback = WorkerCallback(process_id=41, status="ok", output="done", task="run the unused test")
    proc = await writer("a library printed this", encode(Done(process_id=41, callback=callback)).strip())
    worker = await watch(proc, endings, 41)
    assert await endings.wait(41) == callback
    assert worker.job is None
    os.killpg(proc.pid, signal.SIGKILL)  # the exit that follows must not report the job again
    await worker.exited.wait()
    assert len(endings.reports[41]) == 1


async def test_an_end_the_pool_cannot_read_ends_the_job_as_an_error_not_never() -> None:
    endings = Endings()
    bad = '{"event":"done","process_id":42,"callback":{"process_id":42,"status":"meh"}}'
    proc = await writer(bad)
    worker = await watch(proc, endings, 42)
    callback = await endings.wait(42)
    assert callback.status == "error"
    assert "invalid end of the process" in (callback.error or "")
    os.killpg(proc.pid, signal.SIGKILL)
    await worker.exited.wait()
    assert len(endings.reports[42]) == 1
