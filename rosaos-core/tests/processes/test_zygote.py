"""A fork server forked from the kernel (``rosaos up``'s zygote) serves, parks and dies like any other.

The "kernel" is a subprocess that calls :func:`rosaos.processes.zygote.prefork` as ``rosaos up``
does, then starts a pool with one warm worker and prints the pids. Its fork server must be the
kernel's own child (so the two share pages) and fork the workers; killing the kernel must end the
workers, and must not leave the kernel's stdout held open by the parked server. The next pool
adopts that server and runs a job on a worker it forks.
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
    make_job,
    parent_pid,
    pid_alive,
    wait_until_dead,
    wait_until_parked,
    worker_env,
)

pytestmark = [pytest.mark.slow, pytest.mark.asyncio(loop_scope="module")]

KERNEL_WITH_ZYGOTE = """
import asyncio, json, os, sys
from rosaos.processes import zygote
from rosaos.processes.pool import WorkerPool

forked = zygote.prefork()

async def main():
    pool = WorkerPool(size=1, env=json.loads(sys.argv[2]), park=sys.argv[1] or None)
    await pool.start()
    pids = {
        "kernel": os.getpid(),
        "zygote": forked.pid if forked else None,
        "server": pool.fork_server.pid if pool.fork_server.ready else None,
        "workers": [row.pid for row in pool.stats()],
    }
    print(json.dumps(pids), flush=True)
    await asyncio.sleep(600)

asyncio.run(main())
"""


def killed_kernel(name: str | None) -> dict[str, object]:
    """Run the kernel stand-in until its pool is warm, then SIGKILL it; the pids it printed."""
    kernel = subprocess.Popen(
        [sys.executable, "-c", KERNEL_WITH_ZYGOTE, name or "", json.dumps(worker_env())],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert kernel.stdout is not None
    line = kernel.stdout.readline()
    try:
        pids = json.loads(line)
        server = pids["server"]
        assert server is not None and server == pids["zygote"], f"the forked zygote does not serve: {line}"
        assert parent_pid(server) == pids["kernel"], "the fork server is not the kernel's own child"
        assert pids["workers"] and all(parent_pid(pid) == server for pid in pids["workers"])
    finally:
        kernel.kill()
        # EOF at once: no process of the tree (the parked server above all) holds the kernel's stdout.
        rest, _ = kernel.communicate(timeout=30)
    assert rest == ""
    return pids


async def test_a_kernel_killed_ends_its_workers_and_the_next_adopts_its_forked_fork_server(
    tmp_path: Path, kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    name = park_name(tmp_path)
    pids = killed_kernel(name)
    for worker in pids["workers"]:  # type: ignore[attr-defined]
        wait_until_dead(worker, within=30)
    server = pids["server"]
    assert isinstance(server, int) and pid_alive(server), "the forked fork server did not outlive its kernel"
    wait_until_parked(name)
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
    wait_until_dead(server, within=30)


async def test_without_parking_the_forked_fork_server_and_its_workers_die_with_the_kernel() -> None:
    pids = killed_kernel(None)
    for pid in [pids["server"], *pids["workers"]]:  # type: ignore[list-item]
        assert isinstance(pid, int)
        wait_until_dead(pid, within=30)
