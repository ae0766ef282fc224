"""``rosaos up`` starts its devices without waiting for them: each becomes usable as it comes up.

``start(wait=False)`` returns while the shared host still starts its instances; they are
``starting`` (and recorded so in the run file), each one gets its URL and turns ``healthy`` as the
host reports it, ``settle`` waits for named ones, and the run file catches up.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from rosaos.devices.client import DeviceClient
from rosaos.devices.run_files import run_file_path
from rosaos.devices.supervisor import DeviceSupervisor

from .devices_support import drivers_for_tests, eventually, requires_tapo, world_of

TOKEN = "start-without-waiting-token"
FAST: dict[str, Any] = {"health_interval": 0.2, "health_timeout": 2.0, "backoff_base": 0.1, "stop_grace": 2.0}
LAMPS = 6

pytestmark = [pytest.mark.asyncio, requires_tapo]


def recorded(data_dir: Path) -> dict[str, str]:
    devices = json.loads(run_file_path(data_dir).read_text())["devices"]
    return {name: row["status"] for name, row in devices.items()}


async def test_instances_of_the_shared_host_come_up_one_by_one_after_start_returns(data_dir: Path) -> None:
    lamps = {f"lamp_{k}": {"driver": "tapo", "sim": {"on": False}} for k in range(LAMPS)}
    world = world_of(drivers_for_tests(with_tapo=True), data_dir, **lamps)
    supervisor = DeviceSupervisor(world, data_dir, TOKEN, **FAST)
    try:
        await supervisor.start(wait=False)
        # Returned before the host could even start: every lamp is starting, and says so on disk.
        assert {entry.status for entry in supervisor.directory().values()} == {"starting"}
        assert set(recorded(data_dir).values()) == {"starting"}
        await supervisor.settle(["lamp_0"])
        first = supervisor.directory()["lamp_0"]
        assert first.status == "healthy" and first.url is not None
        state = await DeviceClient(first.url, TOKEN, 10.0, "lamp_0").get_state()
        assert state["on"] is False
        await supervisor.settle(lamps)
        directory = supervisor.directory()
        assert {entry.status for entry in directory.values()} == {"healthy"}
        assert len({entry.url for entry in directory.values()}) == LAMPS
        await eventually(lambda: set(recorded(data_dir).values()) == {"healthy"}, within=10)
    finally:
        await supervisor.stop()
