"""A device host starts latched from its first moment when the emergency stop is latched.

Before, a host that started (or restarted) while the kernel was latched ran tool calls until the
kernel's next push reached it, up to 2 s later. Now the latch is kept in the data directory: the
kernel writes it before it starts any host, and a host writes what it is told, so the first tool
call a new host serves is already refused.
"""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

import httpx
import pytest

from rosaos.devices.client import DeviceClient
from rosaos.devices.latch import LATCH_FILE
from rosaos.devices.serve import open_device, serve_http
from rosaos.devices.world import World
from rosaos.drivers import DeviceError
from rosaos.kernel.host_latch import keep_latch
from rosaos.processes.manager import EmergencyStop

from .devices_support import drivers_for_tests, world_of

TOKEN = "test-token"


def lamp_world(data_dir: Path) -> World:
    return world_of(drivers_for_tests(), data_dir, lamp={"driver": "tiny", "sim": {"on": True}})


async def first_switch(data_dir: Path) -> str:
    """Start the lamp's host and make its very first call one that acts; the error text, or "accepted"."""
    async with (
        open_device(lamp_world(data_dir).get("lamp"), data_dir) as device,
        serve_http(device.server, TOKEN) as http,
    ):
        client = DeviceClient(http.url, TOKEN)
        try:
            await client.call("switch", {"on": False})
        except DeviceError as error:
            return str(error)
        return "accepted"


async def test_a_host_started_while_the_kernel_is_latched_refuses_its_first_call(data_dir: Path) -> None:
    keep_latch(data_dir, EmergencyStop(reason="pressed on the page", time=datetime.now(UTC)))
    refused = await first_switch(data_dir)
    assert "emergency stop is latched (pressed on the page)" in refused


async def test_a_host_started_after_a_reset_acts(data_dir: Path) -> None:
    keep_latch(data_dir, EmergencyStop(reason="pressed", time=datetime.now(UTC)))
    keep_latch(data_dir, None)
    assert await first_switch(data_dir) == "accepted"


async def tell(data_dir: Path, latched: bool, reason: str) -> None:
    """Start the lamp's host, tell it the latch as the kernel does (``POST /latch``), and stop it."""
    async with (
        open_device(lamp_world(data_dir).get("lamp"), data_dir) as device,
        serve_http(device.server, TOKEN) as http,
        httpx.AsyncClient(headers={"Authorization": f"Bearer {TOKEN}"}) as api,
    ):
        url = http.url.removesuffix("/mcp") + "/latch"
        (await api.post(url, json={"latched": latched, "reason": reason})).raise_for_status()


async def test_a_host_that_was_told_the_latch_restarts_latched_until_told_the_reset(data_dir: Path) -> None:
    await tell(data_dir, True, "estop")
    assert "emergency stop is latched (estop)" in await first_switch(data_dir)  # restarted: still latched
    await tell(data_dir, False, "")
    assert await first_switch(data_dir) == "accepted"


def keep_text(data_dir: Path, text: str) -> None:
    data_dir.mkdir(parents=True, exist_ok=True)
    (data_dir / LATCH_FILE).write_text(text)


@pytest.mark.parametrize("kept", ["{not json", '{"latched": "maybe"}'])
async def test_a_kept_latch_that_cannot_be_read_starts_the_host_latched(data_dir: Path, kept: str) -> None:
    keep_text(data_dir, kept)
    refused = await first_switch(data_dir)
    assert "could not be read" in refused
