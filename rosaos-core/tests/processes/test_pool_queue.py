"""The pool's cap on live workers: jobs beyond ``max_workers`` wait in order and are not refused."""

from __future__ import annotations

from collections.abc import AsyncIterator

import pytest
import pytest_asyncio

from rosaos.processes.capacity import LEAST, default_max_workers
from rosaos.processes.pool import WorkerPool

from .processes_support import Endings, KernelStandIn, LoopbackDevice, make_job, worker_env

pytestmark = [pytest.mark.slow, pytest.mark.asyncio(loop_scope="module")]


@pytest_asyncio.fixture(loop_scope="module")
async def capped() -> AsyncIterator[tuple[WorkerPool, Endings]]:
    endings = Endings()
    pool = WorkerPool(size=1, env=worker_env(), on_ended=endings.record, kill_grace=3.0, max_workers=1)
    await pool.start()
    yield pool, endings
    await pool.stop()


async def test_jobs_beyond_the_cap_wait_in_order_and_all_run(
    capped: tuple[WorkerPool, Endings], kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    pool, endings = capped
    # A sleeper that stops itself at its timeout holds the one slot; three jobs queue behind it.
    sleeper = make_job(kernel, "sleeps", timeout=2)
    waiting = [make_job(kernel, "sets_level", [devices["lamp"]]) for _ in range(3)]
    first = await pool.run(sleeper)
    assert first.worker_pid is not None and first.queued == 0
    handles = [await pool.run(job) for job in waiting]
    assert [(h.worker_pid, h.queued) for h in handles] == [(None, 1), (None, 2), (None, 3)]
    assert pool.queued() == 3
    assert len(pool.stats()) == 1  # no worker beyond the cap was started
    for job in waiting:
        callback = await endings.wait(job.process_id)
        assert callback.status == "ok"
    assert (await endings.wait(sleeper.process_id)).status == "timeout"
    order = list(endings.reports)
    assert order == [sleeper.process_id, *(job.process_id for job in waiting)]  # first come, first run
    assert pool.queued() == 0


async def test_a_queued_job_can_be_terminated_before_it_starts(
    capped: tuple[WorkerPool, Endings], kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    pool, endings = capped
    sleeper = make_job(kernel, "sleeps", timeout=2)
    queued = make_job(kernel, "sets_level", [devices["lamp"]])
    after = make_job(kernel, "sets_level", [devices["lamp"]])
    await pool.run(sleeper)
    await pool.run(queued)
    await pool.run(after)
    assert await pool.terminate(queued.process_id)
    callback = await endings.wait(queued.process_id)
    assert callback.status == "terminated"
    assert pool.queued() == 1
    assert (await endings.wait(after.process_id)).status == "ok"
    assert not await pool.terminate(queued.process_id)


async def test_the_default_cap_is_sized_to_the_machine() -> None:
    assert default_max_workers() >= LEAST
    assert WorkerPool(size=2).max_workers == default_max_workers()
    assert WorkerPool(size=8, max_workers=3).max_workers == 8  # never below the warm pool
