"""A command right after ``rosaos up``'s banner: its device or the warm pool may still be starting.

The banner no longer waits for every device (a hundred lamps take seconds) nor for the warm pool,
so a launch that names a device still ``starting`` waits briefly for it, and one that arrives
while the pool is still importing waits for the pool; neither is lost. A device that does not
come up in time is refused with a reason that says it is still starting. Real workers and a
real loopback device; only the "still starting" status is staged.
"""

from __future__ import annotations

import asyncio
import dataclasses

import pytest

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.processes.manager import LaunchRefused, ProcessManager
from rosaos.processes.pool import WorkerPool

from .processes_support import KERNEL_TOKEN, Endings, KernelStandIn, LoopbackDevice, model_spec, worker_env

pytestmark = pytest.mark.asyncio(loop_scope="module")


class StartingLamp:
    """The lamp's endpoint as the supervisor shows it: ``starting`` without a URL until ``up()``."""

    def __init__(self, lamp: LoopbackDevice) -> None:
        self.served = lamp.endpoint()
        self.endpoint = dataclasses.replace(self.served, url=None, status="starting")
        self.settled = asyncio.Event()
        self.asked: list[list[str]] = []

    def endpoints(self) -> dict[str, DeviceEndpoint]:
        return {"lamp": self.endpoint}

    def up(self) -> None:
        self.endpoint = self.served
        self.settled.set()

    async def settle(self, names: list[str]) -> None:
        self.asked.append(names)
        await self.settled.wait()


def manager_for(lamp: StartingLamp, kernel: KernelStandIn, endings: Endings, wait: float) -> ProcessManager:
    return ProcessManager(
        devices=lamp.endpoints,
        model=model_spec("by_task"),
        base_prompt="You are a test process.",
        job_timeout=60,
        request_limit=10,
        kernel_url=kernel.url,
        kernel_token=KERNEL_TOKEN,
        pool=WorkerPool(size=1, env=worker_env()),
        on_ended=endings.record,
        starting=lamp.settle,
        starting_wait=wait,
    )


async def test_a_launch_waits_for_its_device_still_starting_and_for_the_pool_still_warming(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp, endings = StartingLamp(devices["lamp"]), Endings()
    manager = manager_for(lamp, kernel, endings, wait=30.0)
    warming = manager.start_in_background()
    try:
        launch = asyncio.create_task(manager.launch("set the lamp level", ["lamp"]))
        await asyncio.sleep(0.3)
        assert not launch.done()  # waiting for the lamp, not refused
        assert lamp.asked == [["lamp"]]
        lamp.up()
        info = await asyncio.wait_for(launch, 60)
        assert warming.done() and warming.exception() is None  # the launch waited for the pool too
        callback = await endings.wait(info.id)
        assert callback.status == "ok"
        assert devices["lamp"].state["level"] == 42
    finally:
        await manager.stop()


async def test_a_device_that_does_not_come_up_in_time_is_refused_as_still_starting(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp, endings = StartingLamp(devices["lamp"]), Endings()
    manager = manager_for(lamp, kernel, endings, wait=0.2)
    try:
        with pytest.raises(LaunchRefused, match="lamp is still starting"):
            await manager.launch("set the lamp level", ["lamp"])
        assert manager.list() == []
        assert manager.leases.held_by(manager.next_process_id) == []
    finally:
        await manager.stop()


async def test_a_device_known_down_is_refused_at_once_without_waiting(
    kernel: KernelStandIn, devices: dict[str, LoopbackDevice]
) -> None:
    lamp, endings = StartingLamp(devices["lamp"]), Endings()
    lamp.endpoint = dataclasses.replace(lamp.served, url=None, status="restarting")
    manager = manager_for(lamp, kernel, endings, wait=30.0)
    try:
        async with asyncio.timeout(5):
            with pytest.raises(LaunchRefused, match=r"not available now \(status: restarting\)"):
                await manager.launch("set the lamp level", ["lamp"])
        assert lamp.asked == []
    finally:
        await manager.stop()
