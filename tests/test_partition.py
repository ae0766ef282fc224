"""A robot stops when the link to its host goes quiet, and its lease is free soon after the link heals.

The robot dog is served by ``rosaos serve-device`` on its own, as on a robot's own computer. The
kernel reaches it only through :class:`~blackhole.Blackhole`, a loopback proxy that can stop
forwarding bytes without closing anything: packets dropped, connections left open, as a firewall
rule or a dead Wi-Fi link would leave them. The dog is told to walk 10 m; mid-walk the link goes
silent. The host hears nothing more from the worker that owns the motion, and its deadman stops
the dog. When the link comes back, the worker learns its motion was ended, the process ends with
the reason, and the dog's lease is free.
"""

from __future__ import annotations

import asyncio
import signal
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from rosaos.devices.client import DeviceClient

from .blackhole import blackhole
from .cli_process import line_matching
from .test_orphans_after_kernel_kill import start, start_kernel

STOP_BOUND = 2.0
"""The robot must be still within this many seconds of the link going quiet (the issue's bound)."""
FREE_BOUND = 5.0
"""The lease must be free within this many seconds of the link coming back."""


@pytest.fixture
def dog(tmp_path: Path) -> Iterator[tuple[str, str]]:
    """The dog on the rosbridge simulator, served on its own; yields its URL and token."""
    config = tmp_path / "robot.toml"
    config.write_text(
        f'data_dir = "{tmp_path / "robot-data"}"\n'
        '[devices.dog]\ndriver = "ros"\nprofile = "puppypi"\n'
        'description = "Hiwonder PuppyPi robot dog"\n'
    )
    served = start("serve-device", "dog", "--config", str(config), "--port", "0")
    try:
        url = line_matching(served, r"(http://127\.0\.0\.1:\d+/mcp)").group(1)
        yield url, (tmp_path / "robot-data" / "token").read_text().strip()
    finally:
        served.send_signal(signal.SIGINT)
        try:
            served.wait(30)
        except subprocess.TimeoutExpired:
            served.kill()


def dog_state(url: str, token: str) -> dict[str, Any]:
    async def read() -> dict[str, Any]:
        async with DeviceClient(url, token, 10, "dog") as client:
            return await client.get_state()

    return asyncio.run(read())


def wait_for(check: Any, timeout: float, what: str) -> float:
    """Poll ``check`` until truthy; return the seconds it took."""
    started = time.monotonic()
    while time.monotonic() - started < timeout:
        if check():
            return time.monotonic() - started
        time.sleep(0.05)
    raise AssertionError(f"{what}: not within {timeout} s")


def holders(api: httpx.Client, device: str) -> list[dict[str, Any]]:
    return [p for p in api.get("/processes").json() if device in p["devices"]]


def test_a_silent_link_stops_the_robot_and_a_healed_one_frees_its_lease(
    dog: tuple[str, str], tmp_path: Path
) -> None:
    dog_url, dog_token = dog
    port = int(dog_url.rsplit(":", 1)[1].split("/")[0])
    with blackhole(port) as link:
        config = tmp_path / "rosaos.toml"
        config.write_text(
            f'data_dir = "{tmp_path / "data"}"\n[kernel]\npool_size = 1\n'
            f'[devices.dog]\ndriver = "ros"\nurl = "http://127.0.0.1:{link.port}/mcp"\n'
            f'token = "{dog_token}"\ndescription = "Hiwonder PuppyPi robot dog"\n'
        )
        kernel, url = start_kernel(config)
        token = (tmp_path / "data" / "token").read_text().strip()
        try:
            with httpx.Client(base_url=url, headers={"Authorization": f"Bearer {token}"}, timeout=10) as api:
                api.post("/chat", json={"text": "make the dog walk forward 10 meters"}).raise_for_status()
                # 180 s: the banner does not wait for the warm pool, so on a busy machine the
                # first command also waits for the fork server's imports.
                wait_for(lambda: dog_state(dog_url, dog_token)["x"] > 0.2, 180, "the dog walking")

                link.silence()
                # Read the dog on its own host, around the proxy: only the kernel's link is cut.
                stopped_after = wait_for(
                    lambda: dog_state(dog_url, dog_token)["linear"] == 0.0, 10, "the dog stopping"
                )
                held_x = dog_state(dog_url, dog_token)["x"]
                time.sleep(4.0)  # a partition of several seconds; the process still holds the dog
                still_x = dog_state(dog_url, dog_token)["x"]
                during = holders(api, "dog")

                link.heal()
                freed_after = wait_for(lambda: not holders(api, "dog"), 30, "the dog's lease freed")
                ended = [
                    u
                    for u in api.get("/updates", params={"after": 0, "limit": 1000}).json()["updates"]
                    if u["kind"] == "process_ended"
                ]
        finally:
            kernel.send_signal(signal.SIGINT)
            kernel.wait(60)
    assert stopped_after < STOP_BOUND, (
        f"the dog was still moving {stopped_after:.1f} s after its link went quiet"
    )
    assert still_x == pytest.approx(held_x, abs=0.02), "the dog moved again during the partition"
    assert held_x < 5.0, "the dog walked most of its way: nothing stopped it"
    assert during, "the process let go of the dog before the link came back (nothing to test)"
    assert freed_after < FREE_BOUND, f"the lease was free only {freed_after:.1f} s after the link came back"
    assert ended and ended[-1]["data"]["status"] != "ok", ended
    assert "unreachable" in ended[-1]["data"]["error"] or "deadman" in ended[-1]["data"]["error"], ended


def test_a_safe_stop_that_could_not_be_delivered_is_retried_when_the_link_heals(
    dog: tuple[str, str], tmp_path: Path
) -> None:
    dog_url, dog_token = dog
    port = int(dog_url.rsplit(":", 1)[1].split("/")[0])
    with blackhole(port) as link:
        config = tmp_path / "rosaos.toml"
        config.write_text(
            f'data_dir = "{tmp_path / "data"}"\n[kernel]\npool_size = 1\n'
            f'[devices.dog]\ndriver = "ros"\nurl = "http://127.0.0.1:{link.port}/mcp"\n'
            f'token = "{dog_token}"\ndescription = "Hiwonder PuppyPi robot dog"\n'
        )
        kernel, url = start_kernel(config)
        token = (tmp_path / "data" / "token").read_text().strip()
        headers = {"Authorization": f"Bearer {token}"}
        try:
            with httpx.Client(base_url=url, headers=headers, timeout=10) as api:
                api.post("/chat", json={"text": "make the dog walk forward 10 meters"}).raise_for_status()
                # 180 s: the banner does not wait for the warm pool, so on a busy machine the
                # first command also waits for the fork server's imports.
                wait_for(lambda: dog_state(dog_url, dog_token)["x"] > 0.2, 180, "the dog walking")
                link.silence()
        finally:
            kernel.send_signal(signal.SIGKILL)
            kernel.wait()
        kernel, url = start_kernel(config)  # the dog cannot be told: its safe_stop is owed
        try:
            with httpx.Client(base_url=url, headers=headers, timeout=10) as api:
                crashed = [
                    u
                    for u in api.get("/updates", params={"after": 0, "limit": 1000}).json()["updates"]
                    if u["kind"] == "process_ended"
                ]
                refused = api.post("/chat", json={"text": "make the dog walk forward half a meter"})
                refused.raise_for_status()
                time.sleep(3.0)
                link.heal()

                def retried() -> bool:
                    updates = api.get("/updates", params={"after": 0, "limit": 1000}).json()["updates"]
                    return any("was retried and done" in u["text"] for u in updates)

                wait_for(retried, 20, "the owed safe_stop retried and reported")
                updates = api.get("/updates", params={"after": 0, "limit": 1000}).json()["updates"]
        finally:
            kernel.send_signal(signal.SIGINT)
            kernel.wait(60)
    assert crashed and "dog NOT safe-stopped" in crashed[-1]["data"]["error"], crashed
    texts = [u["text"] for u in updates]
    assert any("owes a safe_stop" in text or "is not available" in text for text in texts), texts
    launched = [u["data"]["process_id"] for u in updates if u["kind"] == "process_launched"]
    assert launched == [1], f"a process got the dog before its owed stop landed: {launched}"
