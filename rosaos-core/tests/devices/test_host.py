"""The device host subprocess: one job in on stdin, one JSON line out, serve until told to stop."""

from __future__ import annotations

import asyncio
import json
import signal
import sys
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest

from rosaos.auth import load_or_create_token, token_path
from rosaos.devices.client import DeviceClient
from rosaos.devices.host import HostJob
from rosaos.drivers import DeviceError

from .devices_support import drivers_for_tests, requires_tapo, world_of

pytestmark = pytest.mark.slow


def tapo_job(data_dir: Path, **changes: Any) -> HostJob:
    load_or_create_token(data_dir)
    fields: dict[str, Any] = {
        "instance": "kitchen_light",
        "driver": "tapo",
        "backend": "sim",
        "sim": {"on": True, "brightness": 40},
        "description": "Ceiling light in the kitchen",
        "data_dir": data_dir,
        "token_file": token_path(data_dir),
    }
    return HostJob(**(fields | changes))


async def start_host(job_line: str) -> asyncio.subprocess.Process:
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosaos.devices.host",
        stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.DEVNULL,
    )
    assert process.stdin is not None
    process.stdin.write(job_line.encode() + b"\n")
    await process.stdin.drain()
    return process


async def handshake(process: asyncio.subprocess.Process) -> dict[str, Any]:
    assert process.stdout is not None
    async with asyncio.timeout(60):
        line = await process.stdout.readline()
    reply = json.loads(line)
    assert isinstance(reply, dict)
    return reply


@pytest.fixture
async def host(data_dir: Path) -> AsyncIterator[tuple[asyncio.subprocess.Process, dict[str, Any]]]:
    process = await start_host(tapo_job(data_dir).model_dump_json())
    try:
        yield process, await handshake(process)
    finally:
        if process.returncode is None:
            process.kill()
            await process.wait()


def test_a_job_keeps_secret_settings_for_the_host(data_dir: Path) -> None:
    world = world_of(drivers_for_tests(), data_dir, lamp={"driver": "tiny", "secret": "hunter2"})
    job = HostJob.for_instance(world.get("lamp"), data_dir, token_path(data_dir), None)
    assert json.loads(job.model_dump_json())["settings"] == {"secret": "hunter2"}


@requires_tapo
async def test_host_serves_the_instance_until_sigterm_then_exits_0(
    host: tuple[asyncio.subprocess.Process, dict[str, Any]], data_dir: Path
) -> None:
    process, reply = host
    assert reply["pid"] == process.pid
    state = await DeviceClient(reply["url"], load_or_create_token(data_dir), timeout=10).get_state()
    assert state["on"] is True
    assert state["brightness"] == 40
    process.send_signal(signal.SIGTERM)
    async with asyncio.timeout(15):
        assert await process.wait() == 0


@requires_tapo
async def test_host_stops_when_its_supervisor_goes_away(
    host: tuple[asyncio.subprocess.Process, dict[str, Any]],
) -> None:
    process, _ = host
    assert process.stdin is not None
    process.stdin.close()  # what the kernel does for us when the supervisor dies
    async with asyncio.timeout(15):
        assert await process.wait() == 0


def test_a_job_for_an_unknown_driver_names_the_installed_ones(data_dir: Path) -> None:
    with pytest.raises(DeviceError, match=r"kitchen_light: unknown driver 'nope'; installed drivers: "):
        tapo_job(data_dir, driver="nope").resolve()
