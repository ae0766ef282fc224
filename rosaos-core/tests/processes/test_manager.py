"""The process manager: leases first, then a real worker; leases released however a process ends.

The processes run the ``by_task`` test model in real worker subprocesses: a task that says
"sleep" hangs until stopped, any other task sets the level of its devices to 42.
"""

from __future__ import annotations

import asyncio
import os
import signal
from collections.abc import AsyncIterator
from datetime import UTC, datetime

import pytest
import pytest_asyncio

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.events.callback import WorkerCallback
from rosaos.events.plan import Plan, PlanStep
from rosaos.processes.manager import EmergencyStop, LaunchRefused, ProcessManager
from rosaos.processes.pool import WorkerPool

from .processes_support import (
    KERNEL_TOKEN,
    Endings,
    KernelStandIn,
    LoopbackDevice,
    model_spec,
    pid_alive,
    worker_env,
)

pytestmark = [pytest.mark.slow, pytest.mark.asyncio(loop_scope="module")]

FIRST_ID = 100


def world(devices: dict[str, LoopbackDevice]) -> dict[str, DeviceEndpoint]:
    """``lamp`` is exclusive; ``fan`` is shared and always attached, like the Reachy Mini."""
    return {
        "lamp": devices["lamp"].endpoint("exclusive"),
        "fan": devices["fan"].endpoint("shared", always_attached=True),
    }


def new_manager(
    devices: dict[str, LoopbackDevice],
    kernel: KernelStandIn,
    endings: Endings,
    pool_size: int,
    emergency_stop: EmergencyStop | None = None,
) -> ProcessManager:
    endpoints = world(devices)
    return ProcessManager(
        devices=lambda: endpoints,
        model=model_spec("by_task"),
        base_prompt="You are a test process.",
        job_timeout=60,
        request_limit=10,
        kernel_url=kernel.url,
        kernel_token=KERNEL_TOKEN,
        pool=WorkerPool(size=pool_size, env=worker_env()),
        on_ended=endings.record,
        first_process_id=FIRST_ID,
        emergency_stop=emergency_stop,
    )


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def running(
    devices: dict[str, LoopbackDevice], kernel: KernelStandIn
) -> AsyncIterator[tuple[ProcessManager, Endings]]:
    endings = Endings()
    manager = new_manager(devices, kernel, endings, pool_size=1)
    await manager.start()
    yield manager, endings
    await manager.stop()


@pytest_asyncio.fixture(loop_scope="module")
async def manager(running: tuple[ProcessManager, Endings]) -> ProcessManager:
    """The module's manager, its warm worker ready and no process running."""
    manager = running[0]
    async with asyncio.timeout(60):
        await manager.pool.wait_until_warm()
    assert manager.list() == []
    return manager


@pytest.fixture
def endings(running: tuple[ProcessManager, Endings]) -> Endings:
    """What the manager passed on to the kernel's ``on_ended``."""
    return running[1]


async def test_launch_returns_at_once_and_the_ended_process_releases_its_leases(
    manager: ProcessManager, endings: Endings, kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    info = await manager.launch("set the lamp level", ["lamp"])
    assert info.id >= FIRST_ID
    assert (info.state, info.devices) == ("running", ["lamp", "fan"])
    assert info.worker_pid is not None
    assert pid_alive(info.worker_pid)
    assert manager.leases.held_by(info.id) == ["lamp", "fan"]
    callback = await endings.wait(info.id)
    assert callback.status == "ok"
    ended = manager.get(info.id)
    assert ended.state == "ok"
    assert ended.ended_at is not None
    assert manager.leases.held_by(info.id) == []
    assert devices["lamp"].state["level"] == devices["fan"].state["level"] == 42


async def test_held_lamp_is_refused_until_its_holders_worker_is_killed(
    manager: ProcessManager, endings: Endings
) -> None:
    holder = await manager.launch("sleep with the lamp", ["lamp"])
    with pytest.raises(LaunchRefused) as refused:
        await manager.launch("set the lamp level", ["lamp"])
    assert str(refused.value) == (
        f"lamp is held by process {holder.id} ('sleep with the lamp'); "
        f"wait for it, or terminate_process({holder.id})"
    )
    assert holder.worker_pid is not None
    os.kill(holder.worker_pid, signal.SIGKILL)
    callback = await endings.wait(holder.id)
    assert callback.status == "crashed"
    assert "killed by SIGKILL" in (callback.error or "")
    assert manager.get(holder.id).state == "crashed"
    assert "lamp" not in manager.leases.holders()


async def test_terminate_kills_the_worker_and_releases_the_leases(
    manager: ProcessManager, endings: Endings
) -> None:
    info = await manager.launch("sleep with the lamp", ["lamp"])
    ended = await manager.terminate(info.id)
    assert ended.state == "terminated"
    assert info.worker_pid is not None
    assert not pid_alive(info.worker_pid)
    assert manager.leases.held_by(info.id) == []
    assert (await endings.wait(info.id)).status == "terminated"
    assert await manager.terminate(info.id) == ended


async def test_recorded_callback_ends_the_process_and_the_later_report_changes_nothing(
    manager: ProcessManager, endings: Endings
) -> None:
    info = await manager.launch("set the lamp level", ["lamp"])
    manager.record_callback(WorkerCallback(process_id=info.id, status="ok", output="recorded by the kernel"))
    recorded = manager.get(info.id)
    assert recorded.state == "ok"
    assert manager.leases.held_by(info.id) == []
    await endings.wait(info.id)
    manager.record_callback(WorkerCallback(process_id=info.id, status="error"))
    assert manager.get(info.id) == recorded


async def test_list_shows_running_processes_and_ended_ones_on_request(
    manager: ProcessManager, endings: Endings
) -> None:
    info = await manager.launch("set the lamp level", ["lamp"])
    assert [process.id for process in manager.list()] == [info.id]
    await endings.wait(info.id)
    assert manager.list() == []
    assert info.id in [process.id for process in manager.list(include_ended=True)]


async def test_terminate_of_an_unknown_process_names_the_running_ones(manager: ProcessManager) -> None:
    with pytest.raises(KeyError) as unknown:
        await manager.terminate(99_999)
    assert unknown.value.args[0] == "no process 99999; running processes: none (see list_processes)"


async def test_refused_launches_do_not_use_up_process_ids(
    devices: dict[str, LoopbackDevice], kernel: KernelStandIn
) -> None:
    manager = new_manager(devices, kernel, Endings(), pool_size=0)  # never started: refusals stop first
    with pytest.raises(LaunchRefused, match="unknown device 'oven'; the devices are: fan, lamp"):
        await manager.launch("bake", ["oven"])
    with pytest.raises(LaunchRefused, match="the task is empty"):
        await manager.launch("  ", ["lamp"])
    assert manager.next_process_id == FIRST_ID


async def test_a_manager_created_latched_refuses_launches_naming_the_emergency_stop(
    devices: dict[str, LoopbackDevice], kernel: KernelStandIn
) -> None:
    # What a kernel restarted after an emergency stop builds: the latch comes from its disk.
    latched = EmergencyStop(reason="robot near the stairs", time=datetime(2025, 1, 2, tzinfo=UTC))
    manager = new_manager(devices, kernel, Endings(), pool_size=0, emergency_stop=latched)
    with pytest.raises(
        LaunchRefused,
        match=r"emergency stop is latched \(robot near the stairs\); .* `rosaos estop --reset`",
    ):
        await manager.launch("set the lamp level", ["lamp"])
    assert manager.next_process_id == FIRST_ID


async def test_stopping_again_replaces_the_reason_and_time_and_reset_unlatches(
    devices: dict[str, LoopbackDevice], kernel: KernelStandIn
) -> None:
    manager = new_manager(devices, kernel, Endings(), pool_size=0)
    assert await manager.latch_emergency_stop("first") == []
    first = manager.emergency_stop
    await manager.latch_emergency_stop("second")
    assert manager.emergency_stop is not None and first is not None
    assert manager.emergency_stop.reason == "second"
    assert manager.emergency_stop.time >= first.time
    manager.reset_emergency_stop()
    assert manager.emergency_stop is None


async def test_stop_terminates_running_processes_and_kills_every_worker(
    devices: dict[str, LoopbackDevice], kernel: KernelStandIn
) -> None:
    endings = Endings()
    manager = new_manager(devices, kernel, endings, pool_size=0)
    await manager.start()
    info = await manager.launch("sleep with the lamp", ["lamp"])
    assert info.worker_pid is not None
    await manager.stop()
    assert manager.get(info.id).state == "terminated"
    assert not pid_alive(info.worker_pid)
    assert manager.leases.holders() == {}
    assert (await endings.wait(info.id)).status == "terminated"


async def test_terminate_while_the_worker_is_being_spawned_kills_it_once_it_exists(
    devices: dict[str, LoopbackDevice], kernel: KernelStandIn
) -> None:
    endings = Endings()
    manager = new_manager(devices, kernel, endings, pool_size=0)  # every launch spawns a one-off
    process_id = manager.next_process_id
    launching = asyncio.create_task(manager.launch("sleep with the lamp", ["lamp"]))
    await asyncio.sleep(0)  # launch has taken the leases and is waiting for the spawn
    assert (await manager.terminate(process_id)).state == "terminated"
    assert manager.leases.holders() == {}
    info = await launching
    assert info.state == "terminated"
    assert info.worker_pid is not None
    assert not pid_alive(info.worker_pid)
    assert (await endings.wait(process_id)).status == "terminated"
    await manager.stop()


async def test_a_launch_waits_behind_a_short_planned_holder_then_runs_once(
    manager: ProcessManager, endings: Endings, devices: dict[str, LoopbackDevice]
) -> None:
    """ "Turn on the lamp", then at once "make it green": the second runs after the first."""
    plan = Plan(steps=[PlanStep(device="lamp", tool="set_level", args={"level": 10})], reply="Set.")
    first = await manager.launch("set the lamp to 10", ["lamp"], plan=plan)
    assert manager.leases.held_by(first.id)  # the holder still runs when the second arrives
    second = await manager.launch("set the lamp level", ["lamp"])
    assert second.id == first.id + 1
    assert manager.get(first.id).state == "ok"
    assert (await endings.wait(second.id)).status == "ok"
    assert [p.id for p in manager.list(include_ended=True)].count(second.id) == 1
    assert devices["lamp"].state["level"] == 42
