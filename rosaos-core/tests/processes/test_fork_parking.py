"""A fork server outlives a kernel killed with SIGKILL, and the next kernel adopts it, warm.

A "kernel" here is a subprocess whose pool parks its fork server under a name of the test's own
data directory; it is killed with SIGKILL once its fork server is ready. The next pool with the
same name, environment and Python adopts that very server (no imports again) and runs a job on a
worker it forks. A pool that does not fit it (another environment: an API key set since, say) is
refused, the parked server exits, and a fresh one is started.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from rosaos.processes.fork_parking import park_name
from rosaos.processes.pool import WorkerPool

from .processes_support import (
    Endings,
    KernelStandIn,
    LoopbackDevice,
    eventually,
    make_job,
    parent_pid,
    pid_alive,
    wait_until_dead,
    wait_until_parked,
    worker_env,
)

pytestmark = [pytest.mark.slow, pytest.mark.asyncio(loop_scope="module")]

DYING_KERNEL = """
import asyncio, json, sys
from rosaos.processes.pool import WorkerPool

async def main():
    pool = WorkerPool(size=0, env=json.loads(sys.argv[2]), park=sys.argv[1])
    await pool.start()
    print(pool.fork_server.pid if pool.fork_server.ready else "not ready", flush=True)
    await asyncio.sleep(600)

asyncio.run(main())
"""


def parked_fork_server(name: str | None) -> int:
    """Run a kernel stand-in (parking under ``name``, or not) until its fork server is ready,
    SIGKILL it; the server's pid, once it has parked.

    The server parks only after it sees its socket close: a pool started before that finds no
    one parked (CI, loaded, once started the next pool first and so never adopted)."""
    script = DYING_KERNEL if name is not None else DYING_KERNEL.replace("park=sys.argv[1]", "park=None")
    kernel = subprocess.Popen(
        [sys.executable, "-c", script, name or "", json.dumps(worker_env())],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert kernel.stdout is not None
        line = kernel.stdout.readline().strip()
    finally:
        kernel.kill()
        kernel.wait()
    assert line.isdigit(), f"the first kernel's fork server did not start: {line!r}"
    if name is not None:
        wait_until_parked(name)
    return int(line)


async def test_the_next_kernel_adopts_the_fork_server_of_one_that_died_and_forks_from_it(
    tmp_path: Path, kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    name = park_name(tmp_path)
    server = parked_fork_server(name)
    assert pid_alive(server), "the fork server did not outlive its kernel"
    endings = Endings()
    pool = WorkerPool(size=0, env=worker_env(), on_ended=endings.record, park=name)
    await pool.start()
    try:
        assert pool.fork_server is not None
        assert pool.fork_server.adopted and pool.fork_server.pid == server
        job = make_job(kernel, "sets_level", [devices["lamp"]])
        handle = await pool.run(job)
        assert handle.worker_pid is not None and parent_pid(handle.worker_pid) == server
        callback = await endings.wait(job.process_id)
        assert (callback.status, callback.output) == ("ok", "lamp level is 42")
    finally:
        await pool.stop()
    wait_until_dead(server, within=30)  # a kernel that stops (not one that dies) leaves nothing behind


async def test_a_parked_fork_server_that_does_not_fit_exits_and_a_fresh_one_starts(tmp_path: Path) -> None:
    name = park_name(tmp_path)
    server = parked_fork_server(name)
    pool = WorkerPool(size=0, env={**worker_env(), "ROSAOS_TEST_NEW_KEY": "set since"}, park=name)
    await pool.start()
    try:
        assert pool.fork_server is not None
        assert not pool.fork_server.adopted
        await eventually(lambda: pool.fork_server and pool.fork_server.ready, within=120, what="a fresh one")
        assert pool.fork_server.pid not in (None, server)
        wait_until_dead(server, within=30)
    finally:
        await pool.stop()


async def test_a_pool_without_a_park_name_leaves_no_fork_server_behind_when_its_kernel_dies() -> None:
    wait_until_dead(parked_fork_server(None))
