"""A device host that crashes is news on the updates stream, and so is its return."""

from __future__ import annotations

import os
import signal
from pathlib import Path
from typing import Any

from rosaos.devices.run_files import read_runtime_file

from .e2e_support import eventually, kernel_api, running_kernel

WORLD = '[kernel]\npool_size = 0\nfork_server = false\n[devices.kitchen_light]\ndriver = "tapo"\n'


async def test_a_killed_device_host_is_reported_down_then_back(tmp_path: Path) -> None:
    async with running_kernel(tmp_path, WORLD) as kernel, kernel_api(kernel) as api:
        running = read_runtime_file(kernel.data_dir)  # run/devices.json, as `rosaos devices list` reads it
        assert running is not None
        pid = running.devices["kitchen_light"].pid
        assert pid is not None
        os.kill(pid, signal.SIGKILL)

        async def notices() -> list[str]:
            updates: list[dict[str, Any]] = (
                await api.get("/updates", params={"after": 0, "limit": 1000})
            ).json()["updates"]
            texts = [u["text"] for u in updates if u["kind"] == "notice" and "kitchen_light" in u["text"]]
            return texts if any(text.endswith("is back") for text in texts) else []

        texts = await eventually(notices, timeout=60)
    assert texts[0].startswith("device kitchen_light is down (restarting")
    assert texts[-1] == "device kitchen_light is back"
    assert len(texts) == 2
