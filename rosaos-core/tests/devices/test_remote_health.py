"""A remote device's health checks, on a clock the test moves (no real interval passes).

A remote instance is someone else's to restart; the supervisor only asks it ``get_state`` every
``health_interval``. One failed check is a blip, ``unhealthy_after`` in a row make it
``unreachable`` (with the reason), and one answer makes it healthy again. The device is a real
server on loopback, stopped and served again on the same port; only the waiting is the test's.
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

from rosaos.devices.run_files import DeviceStatus
from rosaos.devices.serve import open_device, serve_http
from rosaos.devices.supervisor import DeviceSupervisor
from rosaos.testing.manual_clock import ManualClock

from .devices_support import drivers_for_tests, eventually, world_of

TOKEN = "remote-health-token"
INTERVAL = 5.0  # the default: 15 s before "unreachable", in no time here


@asynccontextmanager
async def far_lamp(data_dir: Path, port: int = 0) -> AsyncIterator[str]:
    """A ``tiny`` lamp served over HTTP on ``port`` (0: any); its URL."""
    lamp = world_of(drivers_for_tests(), data_dir, lamp={"driver": "tiny"}).get("lamp")
    async with open_device(lamp, data_dir) as device, serve_http(device.server, TOKEN, port=port) as served:
        yield served.url


async def test_a_remote_device_is_unreachable_only_after_missed_checks_in_a_row(tmp_path: Path) -> None:
    clock = ManualClock()
    data_dir = tmp_path / "data"

    async def checked(at: float, status: DeviceStatus) -> None:
        """Move the clock to ``at``, let that check run, and see ``status``."""
        await clock.advance(at - clock.now())
        await eventually(lambda: clock.next_wake == at + INTERVAL, within=10)  # checked, asleep again
        assert supervisor.directory()["far"].status == status, supervisor.directory()["far"]

    async with far_lamp(tmp_path / "served") as url:
        world = world_of(drivers_for_tests(), data_dir, far={"driver": "tiny", "url": url})
        supervisor = DeviceSupervisor(world, data_dir, TOKEN, health_interval=INTERVAL, clock=clock)
        await supervisor.start()
    try:
        assert supervisor.directory()["far"].status == "healthy"
        port = int(url.rsplit(":", 1)[1].split("/")[0])
        await checked(5.0, "healthy")  # the lamp is gone: one miss is a blip
        await checked(10.0, "healthy")
        await checked(15.0, "unreachable")  # the third miss in a row
        assert "nothing is listening" in (supervisor.directory()["far"].error or "")
        async with far_lamp(tmp_path / "served", port):
            await checked(20.0, "healthy")  # back: one answer is enough
            assert supervisor.directory()["far"].error is None
    finally:
        await supervisor.stop()
