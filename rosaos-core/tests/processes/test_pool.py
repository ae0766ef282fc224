"""The warm worker pool, with real worker subprocesses and real servers on loopback.

One pool serves the whole module; each test waits until the pool is warm again, so a test that
kills a worker does not change what the next one sees.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from pathlib import Path

import pytest
import pytest_asyncio

from rosaos.processes.pool import PoolError, WorkerPool

from .processes_support import (
    Endings,
    KernelStandIn,
    LoopbackDevice,
    eventually,
    make_job,
    pid_alive,
    worker_env,
)

pytestmark = [pytest.mark.slow, pytest.mark.asyncio(loop_scope="module")]

POOL_SIZE = 1


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def running_pool() -> AsyncIterator[tuple[WorkerPool, Endings]]:
    endings = Endings()
    # The grace is what a stuck worker costs a test, and what a busy machine gives a well-behaved
    # worker to stop its own job: 0.5 s was too little under load (a cooperative timeout was killed).
    pool = WorkerPool(size=POOL_SIZE, env=worker_env(), on_ended=endings.record, kill_grace=3.0)
    await pool.start()
    yield pool, endings
    await pool.stop()


@pytest_asyncio.fixture(loop_scope="module")
async def pool(running_pool: tuple[WorkerPool, Endings]) -> WorkerPool:
    """The module's pool, with all its warm workers ready."""
    async with asyncio.timeout(60):
        await running_pool[0].wait_until_warm()
    return running_pool[0]


@pytest.fixture
def endings(running_pool: tuple[WorkerPool, Endings]) -> Endings:
    return running_pool[1]


def warm_pids(pool: WorkerPool) -> set[int]:
    return {row.pid for row in pool.stats() if not row.one_off}


async def test_job_runs_on_a_warm_worker_and_its_end_comes_over_the_pipe_only(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    before = warm_pids(pool)
    job = make_job(kernel, "sets_level", [devices["lamp"]])
    handle = await pool.run(job)
    assert not handle.one_off
    assert handle.worker_pid in before
    callback = await endings.wait(job.process_id)
    assert (callback.status, callback.output) == ("ok", "lamp level is 42")
    assert kernel.bodies == []  # nothing over HTTP: the pipe is the one route of a process's end
    await eventually(lambda: all(row.state == "idle" for row in pool.stats()), what="the worker to be idle")
    assert warm_pids(pool) == before


async def test_worker_that_exits_mid_task_is_reported_crashed_and_replaced(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    job = make_job(kernel, "exits")
    handle = await pool.run(job)
    callback = await endings.wait(job.process_id)
    assert callback.status == "crashed"
    assert f"pid {handle.worker_pid}" in (callback.error or "")
    assert "exit code 3" in (callback.error or "")
    await pool.wait_until_warm()
    assert len(warm_pids(pool)) == POOL_SIZE
    assert handle.worker_pid not in warm_pids(pool)


async def test_job_past_its_timeout_is_stopped_by_its_worker_which_stays_warm(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    job = make_job(kernel, "sleeps", timeout=0.5)
    handle = await pool.run(job)
    callback = await endings.wait(job.process_id)
    assert callback.status == "timeout"
    assert pid_alive(handle.worker_pid)


async def test_stuck_worker_is_killed_at_the_timeout_and_replaced(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    job = make_job(kernel, "blocks", timeout=0.5)
    handle = await pool.run(job)
    callback = await endings.wait(job.process_id)
    assert callback.status == "timeout"
    assert "worker was killed" in (callback.error or "")
    assert not pid_alive(handle.worker_pid)
    await pool.wait_until_warm()
    assert len(warm_pids(pool)) == POOL_SIZE


async def test_terminate_kills_the_worker_and_reports_terminated(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    job = make_job(kernel, "sleeps")
    handle = await pool.run(job)
    assert await pool.terminate(job.process_id)
    callback = await endings.wait(job.process_id)
    assert callback.status == "terminated"
    assert not pid_alive(handle.worker_pid)
    assert not await pool.terminate(job.process_id)
    await pool.wait_until_warm()
    assert len(warm_pids(pool)) == POOL_SIZE


async def test_one_off_worker_runs_the_job_when_all_warm_workers_are_busy(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    # Sleepers that stop themselves at their timeout keep the warm workers busy, then free them.
    sleepers = [make_job(kernel, "sleeps", timeout=3) for _ in range(POOL_SIZE)]
    for sleeper in sleepers:
        assert not (await pool.run(sleeper)).one_off
    job = make_job(kernel, "sets_level")
    handle = await pool.run(job)
    assert handle.one_off
    assert handle.worker_pid not in warm_pids(pool)
    callback = await endings.wait(job.process_id)
    assert callback.status == "ok"
    await eventually(lambda: not pid_alive(handle.worker_pid), what="the one-off worker to retire")
    for sleeper in sleepers:
        assert (await endings.wait(sleeper.process_id)).status == "timeout"
    assert len(warm_pids(pool)) == POOL_SIZE


async def test_stats_show_each_worker_with_its_memory(pool: WorkerPool) -> None:
    rows = pool.stats()
    assert len(rows) == POOL_SIZE
    assert all(row.state == "idle" and row.process_id is None for row in rows)
    assert all(row.rss_bytes and row.rss_bytes > 10_000_000 for row in rows)


async def test_start_fails_clearly_when_workers_cannot_start() -> None:
    pool = WorkerPool(size=1, python="/bin/false")
    with pytest.raises(
        PoolError, match=r"worker exited during start-up \(exit code 1\); run 'echo \| /bin/false"
    ):
        await pool.start()
    assert pool.stats() == []


async def test_start_fails_clearly_when_python_is_missing() -> None:
    with pytest.raises(PoolError, match="cannot start a worker with /no/such/python"):
        await WorkerPool(size=1, python="/no/such/python").start()


@pytest.mark.parametrize("size", [1, 0], ids=["warm worker", "forked one-off"])
async def test_a_module_in_the_working_directory_does_not_shadow_the_workers_imports(
    size: int,
    kernel: KernelStandIn,
    devices: dict[str, LoopbackDevice],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # `python -m` puts the working directory first on sys.path; a stray file there named like a
    # dependency (h2.py, pydantic_ai.py) must not break the workers started from it.
    (tmp_path / "pydantic_ai.py").write_text("raise ImportError('shadowed by the working directory')\n")
    monkeypatch.chdir(tmp_path)
    endings = Endings()
    shadowed = WorkerPool(size=size, env=worker_env(), on_ended=endings.record)
    try:
        await shadowed.start()
        job = make_job(kernel, "sets_level", [devices["lamp"]])
        await shadowed.run(job)
        callback = await endings.wait(job.process_id)
        assert (callback.status, callback.output) == ("ok", "lamp level is 42")
    finally:
        await shadowed.stop()
