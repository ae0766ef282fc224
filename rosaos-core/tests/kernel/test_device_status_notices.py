"""Device status notices: gathered per host and per second, never one per device per flap."""

from __future__ import annotations

import asyncio

from rosaos.kernel.device_status import DeviceStatusUpdates
from rosaos.kernel.updates import UpdateStream

from .kernel_support import eventually

WINDOW = 0.2


def on_host(name: str) -> str:
    return "shared-sims" if name.startswith("lamp") else name


async def notices(updates: UpdateStream) -> list[str]:
    return [u.text for u in await updates.after(0, 1000) if u.kind == "notice"]


async def test_many_devices_of_one_host_going_down_and_back_make_two_notices(updates: UpdateStream) -> None:
    status = DeviceStatusUpdates(updates, on_host, window=WINDOW)
    for k in range(12):
        status.changed(f"lamp_{k}", "healthy", "restarting", "host was killed by SIGKILL")
    status.changed("robot", "healthy", "restarting", "host exited with code 1")
    await eventually(lambda: status.published == 2)
    for k in range(12):
        status.changed(f"lamp_{k}", "restarting", "starting", None)
        status.changed(f"lamp_{k}", "starting", "healthy", None)
    await eventually(lambda: status.published == 3)
    await eventually(lambda: _count(updates, 3))
    texts = await notices(updates)
    assert texts == [
        "12 devices on host shared-sims are not answering (restarting: host was killed by SIGKILL): "
        "lamp_0, lamp_1, lamp_10, lamp_11, lamp_2, lamp_3, lamp_4, lamp_5, lamp_6, lamp_7 and 2 more; "
        "rosaOS is restarting them",
        "device robot is down (restarting: host exited with code 1); rosaOS is restarting it",
        "12 devices on host shared-sims are back: lamp_0, lamp_1, lamp_10, lamp_11, lamp_2, lamp_3, "
        "lamp_4, lamp_5, lamp_6, lamp_7 and 2 more",
    ]
    back = [u for u in await updates.after(0, 1000) if u.text.endswith("and 2 more")][-1]
    assert back.data["host"] == "shared-sims"
    assert len(back.data["devices"]) == 12


async def _count(updates: UpdateStream, count: int) -> bool:
    return len(await notices(updates)) == count


async def test_a_flap_within_the_window_is_not_news(updates: UpdateStream) -> None:
    status = DeviceStatusUpdates(updates, on_host, window=WINDOW)
    for _ in range(5):
        status.changed("lamp_1", "healthy", "unhealthy", "late")
        status.changed("lamp_1", "unhealthy", "healthy", None)
    await asyncio.sleep(3 * WINDOW)
    assert status.published == 0
    assert await notices(updates) == []
