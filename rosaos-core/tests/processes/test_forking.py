"""One-off workers forked by the fork server, with real processes and real servers on loopback.

The module's pool has no warm workers, so every job is a one-off, forked by the fork server when
it is ready. Tests that kill the fork server leave it to the pool to restart; the next test waits
until it is ready again.
"""

from __future__ import annotations

import asyncio
import json
import os
import signal
from collections.abc import AsyncIterator

import pytest
import pytest_asyncio

from rosaos.models.select import ModelSpec
from rosaos.processes.forking import ForkServer, preload_modules
from rosaos.processes.manager import ProcessManager
from rosaos.processes.pool import WorkerPool

from .processes_support import (
    Endings,
    KernelStandIn,
    LoopbackDevice,
    eventually,
    make_job,
    model_spec,
    module_name,
    parent_pid,
    pid_alive,
    process_running,
    wait_until_dead,
    worker_env,
)

pytestmark = [pytest.mark.slow, pytest.mark.asyncio(loop_scope="module")]


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def running_pool() -> AsyncIterator[tuple[WorkerPool, Endings]]:
    endings = Endings()
    pool = WorkerPool(size=0, env=worker_env(), on_ended=endings.record, kill_grace=0.5)
    await pool.start()
    yield pool, endings
    await pool.stop()


@pytest_asyncio.fixture(loop_scope="module")
async def pool(running_pool: tuple[WorkerPool, Endings]) -> WorkerPool:
    """The module's pool, with its fork server ready."""
    await eventually(lambda: fork_server(running_pool[0]).ready, within=60, what="the fork server")
    return running_pool[0]


@pytest.fixture
def endings(running_pool: tuple[WorkerPool, Endings]) -> Endings:
    return running_pool[1]


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def spawning_pool() -> AsyncIterator[tuple[WorkerPool, Endings]]:
    """A pool with the fork server turned off: a one-off is a new Python process."""
    endings = Endings()
    pool = WorkerPool(size=0, env=worker_env(), on_ended=endings.record, fork_server=False)
    await pool.start()
    yield pool, endings
    await pool.stop()


def fork_server(pool: WorkerPool) -> ForkServer:
    assert pool.fork_server is not None
    return pool.fork_server


def fork_server_pid(pool: WorkerPool) -> int:
    pid = fork_server(pool).pid
    assert pid is not None
    return pid


async def test_one_off_runs_its_job_and_retires(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    job = make_job(kernel, "sets_level", [devices["lamp"]])
    handle = await pool.run(job)
    assert handle.one_off
    callback = await endings.wait(job.process_id)
    assert (callback.status, callback.output) == ("ok", "lamp level is 42")
    await eventually(lambda: not pool.stats(), what="the one-off worker to retire")
    assert not pid_alive(handle.worker_pid)


async def test_one_off_is_a_child_of_the_fork_server_in_its_own_session(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    job = make_job(kernel, "sleeps")
    handle = await pool.run(job)
    assert parent_pid(handle.worker_pid) == fork_server_pid(pool)
    assert os.getpgid(handle.worker_pid) == os.getsid(handle.worker_pid) == handle.worker_pid
    await pool.terminate(job.process_id)


async def test_terminate_kills_a_forked_worker_and_reports_terminated(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    job = make_job(kernel, "sleeps")
    handle = await pool.run(job)
    assert await pool.terminate(job.process_id)
    callback = await endings.wait(job.process_id)
    assert (callback.status, callback.error) == ("terminated", "the process was terminated on request")
    assert not pid_alive(handle.worker_pid)


async def test_forked_worker_killed_by_a_signal_is_reported_crashed_with_that_signal(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    job = make_job(kernel, "sleeps")
    handle = await pool.run(job)
    os.kill(handle.worker_pid, signal.SIGTERM)
    callback = await endings.wait(job.process_id)
    assert callback.status == "crashed"
    assert f"pid {handle.worker_pid}" in (callback.error or "")
    assert "killed by SIGTERM" in (callback.error or "")


async def test_forked_worker_that_exits_mid_task_is_reported_with_its_exit_code(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    job = make_job(kernel, "exits")
    await pool.run(job)
    callback = await endings.wait(job.process_id)
    assert callback.status == "crashed"
    assert "exit code 3" in (callback.error or "")


async def test_stuck_forked_worker_is_killed_at_the_timeout(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    job = make_job(kernel, "blocks", timeout=0.5)
    handle = await pool.run(job)
    callback = await endings.wait(job.process_id)
    assert callback.status == "timeout"
    assert "worker was killed" in (callback.error or "")
    assert not pid_alive(handle.worker_pid)


async def test_two_one_offs_forked_at_once_both_run(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    jobs = [make_job(kernel, "sets_level", [devices[name]]) for name in ("lamp", "fan")]
    handles = await asyncio.gather(*(pool.run(job) for job in jobs))
    assert handles[0].worker_pid != handles[1].worker_pid
    for job in jobs:
        callback = await endings.wait(job.process_id)
        assert callback.status == "ok"
    assert devices["lamp"].state["level"] == devices["fan"].state["level"] == 42


async def test_forked_worker_sees_what_a_spawned_worker_sees(
    pool: WorkerPool,
    endings: Endings,
    spawning_pool: tuple[WorkerPool, Endings],
    kernel: KernelStandIn,
) -> None:
    reports = []
    for one_pool, its_endings in ((pool, endings), spawning_pool):
        job = make_job(kernel, "reports_process")
        await one_pool.run(job)
        callback = await its_endings.wait(job.process_id)
        assert callback.status == "ok", callback.error
        reports.append(json.loads(callback.output or ""))
    forked, spawned = reports
    for report in reports:
        report["environment"].pop("PYTEST_CURRENT_TEST", None)  # which test is running
    assert forked == spawned
    assert forked["main"] == "rosaos.processes.worker"
    assert forked["argv"] == ["worker.py"]
    assert forked["own_session"] and forked["own_group"]


async def test_with_the_fork_server_off_a_one_off_is_a_new_python_process(
    spawning_pool: tuple[WorkerPool, Endings], kernel: KernelStandIn
) -> None:
    pool, endings = spawning_pool
    assert pool.fork_server is None
    job = make_job(kernel, "sleeps")
    handle = await pool.run(job)
    assert handle.one_off
    assert parent_pid(handle.worker_pid) == os.getpid()
    await pool.terminate(job.process_id)
    assert (await endings.wait(job.process_id)).status == "terminated"


async def test_job_runs_on_a_spawned_worker_while_the_fork_server_is_down(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    dead = fork_server_pid(pool)
    os.kill(dead, signal.SIGKILL)
    await eventually(lambda: not fork_server(pool).ready, what="the pool to notice")
    job = make_job(kernel, "sleeps")
    handle = await pool.run(job)
    assert parent_pid(handle.worker_pid) == os.getpid()
    await pool.terminate(job.process_id)
    assert (await endings.wait(job.process_id)).status == "terminated"
    # The pool starts a new fork server.
    await eventually(lambda: fork_server(pool).ready, within=60, what="a new fork server")
    assert fork_server_pid(pool) != dead


async def test_job_still_runs_when_the_fork_server_died_unnoticed(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    os.kill(fork_server_pid(pool), signal.SIGKILL)
    wait_until_dead(fork_server_pid(pool))  # blocking: the pool has no chance to notice
    assert fork_server(pool).ready
    job = make_job(kernel, "sleeps")
    handle = await pool.run(job)
    assert parent_pid(handle.worker_pid) == os.getpid()
    await pool.terminate(job.process_id)
    assert (await endings.wait(job.process_id)).status == "terminated"


async def test_worker_whose_fork_server_dies_is_killed_and_reported_crashed(
    pool: WorkerPool, endings: Endings, kernel: KernelStandIn
) -> None:
    job = make_job(kernel, "sleeps")
    handle = await pool.run(job)
    os.kill(fork_server_pid(pool), signal.SIGKILL)
    callback = await endings.wait(job.process_id)
    assert callback.status == "crashed"
    assert "killed by SIGKILL" in (callback.error or "")
    # No longer the fork server's child, it is reaped by init, maybe a moment later.
    assert not process_running(handle.worker_pid)


async def test_stop_leaves_no_fork_server_and_no_forked_worker_alive(kernel: KernelStandIn) -> None:
    endings = Endings()
    pool = WorkerPool(size=0, env=worker_env(), on_ended=endings.record)
    await pool.start()
    job = make_job(kernel, "sleeps")
    handle = await pool.run(job)
    server = fork_server_pid(pool)
    assert parent_pid(handle.worker_pid) == server
    await pool.stop()
    assert (await endings.wait(job.process_id)).status == "terminated"
    assert not pid_alive(handle.worker_pid)
    assert not pid_alive(server)
    assert fork_server(pool).pid is None


async def test_fork_server_refuses_to_fork_after_a_module_started_a_thread(kernel: KernelStandIn) -> None:
    endings = Endings()
    pool = WorkerPool(
        size=0, env=worker_env(), on_ended=endings.record, preload=[module_name("starts_a_thread")]
    )
    await pool.start()
    try:
        assert "started threads (started-at-import)" in (fork_server(pool).unusable or "")
        job = make_job(kernel, "sleeps")
        handle = await pool.run(job)
        assert parent_pid(handle.worker_pid) == os.getpid()
        await pool.terminate(job.process_id)
    finally:
        await pool.stop()


async def test_process_manager_has_the_fork_server_import_its_model_ahead(kernel: KernelStandIn) -> None:
    pool = WorkerPool(size=0)
    ProcessManager(
        devices=dict,
        model=model_spec("sets_level"),
        base_prompt="",
        job_timeout=1,
        request_limit=1,
        kernel_url=kernel.url,
        kernel_token="",
        pool=pool,
        on_ended=Endings().record,
    )
    assert pool.preload == [module_name("process_test_models")]


@pytest.mark.parametrize(
    ("model", "modules"),
    [
        (None, []),
        ("python:process_test_models:sets_level", ["process_test_models"]),
        ("openai:gpt-5.2", ["pydantic_ai.models.openai"]),
        ("google-gla:gemini-2.5-flash", ["pydantic_ai.models.google"]),
        ("openai-compatible", ["pydantic_ai.models.openai"]),
    ],
)
async def test_modules_imported_ahead_for_a_process_model(model: str | None, modules: list[str]) -> None:
    assert preload_modules(ModelSpec(model=model)) == modules
