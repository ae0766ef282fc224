"""The emergency-stop latch holds at the device hosts, remote ones included.

The dog is served by ``rosaos serve-device`` on its own, as on a robot's own computer; a second
device's host ("ghost") is configured but not running. After ``POST /estop`` a tool call that
reaches the dog directly, with its token, is refused at the dog's host; reading state still works.
The answer, and ``GET /estop``, list the ghost as a host that could not be told. After the reset
the dog moves again.
"""

from __future__ import annotations

import asyncio
import signal
import socket
from pathlib import Path

import httpx

from rosaos.devices.client import DeviceClient
from rosaos.drivers import DeviceError

from .test_orphans_after_kernel_kill import start_kernel
from .test_partition import dog  # noqa: F401  (the fixture)


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


async def drive(url: str, token: str) -> str:
    """A direct MCP call to the dog's drive, past the kernel; the error text if it is refused."""
    try:
        await DeviceClient(url, token, 15, "dog").call("drive", {"linear": 0.1, "duration": 0.3})
    except DeviceError as error:
        return str(error)
    return "accepted"


async def state(url: str, token: str) -> dict[str, object]:
    return await DeviceClient(url, token, 10, "dog").get_state()


def test_a_latched_emergency_stop_is_enforced_by_every_device_host(
    dog: tuple[str, str],  # noqa: F811
    tmp_path: Path,
) -> None:
    dog_url, dog_token = dog
    config = tmp_path / "rosaos.toml"
    config.write_text(
        f'data_dir = "{tmp_path / "data"}"\n[kernel]\npool_size = 1\n'
        f'[devices.dog]\ndriver = "ros"\nurl = "{dog_url}"\ntoken = "{dog_token}"\n'
        'description = "Hiwonder PuppyPi robot dog"\n'
        f'[devices.ghost]\ndriver = "tapo"\nurl = "http://127.0.0.1:{free_port()}/mcp"\ntoken = "x"\n'
        'description = "A lamp whose host is down"\n'
    )
    kernel, url = start_kernel(config)
    token = (tmp_path / "data" / "token").read_text().strip()
    try:
        with httpx.Client(base_url=url, headers={"Authorization": f"Bearer {token}"}, timeout=30) as api:
            stopped = api.post("/estop", json={"reason": "test"}).json()
            refused = asyncio.run(drive(dog_url, dog_token))
            readable = asyncio.run(state(dog_url, dog_token))
            latched = api.get("/estop").json()
            api.post("/estop/reset").raise_for_status()
            after_reset = asyncio.run(drive(dog_url, dog_token))
    finally:
        kernel.send_signal(signal.SIGINT)
        kernel.wait(60)
    assert stopped["latched"] and stopped["untold_hosts"] == ["ghost"], stopped
    assert "emergency stop is latched" in refused and "drive" in refused, refused
    assert "x" in readable
    assert latched["untold_hosts"] == ["ghost"], latched
    assert after_reset == "accepted", after_reset
