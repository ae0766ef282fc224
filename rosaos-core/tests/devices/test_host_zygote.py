"""The first device host forked from the kernel (``rosaos up``'s host zygote) serves, dies and
restarts like a spawned one.

The "kernel" is a subprocess that calls :func:`rosaos.devices.host_zygote.prefork` as ``rosaos up``
does, then runs a device supervisor over two simulated Tapo bulbs and prints its pids. The shared
host must be the kernel's own child (so the two share pages), in a session of its own, and serve
both bulbs. Killed, it is reaped and restarted the usual way (``python -m rosaos.devices.host``);
a killed kernel ends it, as it ends a spawned host (its stdin closes).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rosaos.devices.client import DeviceClient
from rosaos.devices.run_files import run_file_path

from .devices_support import eventually, pid_alive, requires_tapo

pytestmark = [pytest.mark.slow, requires_tapo]

TOKEN = "host-zygote-test-token"

KERNEL_WITH_HOST_ZYGOTE = """
import asyncio, json, os, sys
from pathlib import Path
from rosaos.config import DeviceConfig, RosaosConfig
from rosaos.devices import host_zygote
from rosaos.devices.supervisor import DeviceSupervisor
from rosaos.devices.world import build_world
from rosaos.plugins import load_drivers

data_dir = Path(sys.argv[1])
config = RosaosConfig(
    data_dir=data_dir,
    devices={"kitchen_light": DeviceConfig(driver="tapo"), "desk_lamp": DeviceConfig(driver="tapo")},
)
world = build_world(config, load_drivers(allow={"tapo"}))
forked = host_zygote.prefork()

async def main():
    fast = {"health_interval": 0.2, "health_timeout": 2.0, "backoff_base": 0.1, "stop_grace": 2.0}
    async with DeviceSupervisor(world, data_dir, sys.argv[2], **fast) as supervisor:
        directory = supervisor.directory()
        print(json.dumps({
            "kernel": os.getpid(),
            "zygote": forked.pid if forked else None,
            "urls": {name: entry.url for name, entry in directory.items()},
        }), flush=True)
        await asyncio.sleep(600)

asyncio.run(main())
"""


def host_pids(data_dir: Path) -> dict[str, int | None]:
    devices = json.loads(run_file_path(data_dir).read_text())["devices"]
    return {name: entry["pid"] for name, entry in devices.items()}


def statuses(data_dir: Path) -> set[str]:
    devices = json.loads(run_file_path(data_dir).read_text())["devices"]
    return {entry["status"] for entry in devices.values()}


def parent_pid(pid: int) -> int:
    return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])


def command_line(pid: int) -> str:
    return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()


@pytest.fixture
def kernel(data_dir: Path) -> Iterator[tuple[subprocess.Popen[str], dict[str, object]]]:
    """The stand-in kernel, once its supervisor has every bulb healthy; killed at the end."""
    process = subprocess.Popen(
        [sys.executable, "-c", KERNEL_WITH_HOST_ZYGOTE, str(data_dir), TOKEN],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert process.stdout is not None
    try:
        line = process.stdout.readline()
        assert line, "the stand-in kernel exited before its devices served"
        yield process, json.loads(line)
    finally:
        process.kill()
        process.communicate(timeout=30)


async def test_the_first_host_is_the_kernels_forked_child_in_its_own_session_and_serves(
    data_dir: Path, kernel: tuple[subprocess.Popen[str], dict[str, object]]
) -> None:
    _, printed = kernel
    served = host_pids(data_dir)
    assert printed["zygote"] is not None, "prefork did not fork a zygote"
    assert served["kitchen_light"] == served["desk_lamp"] == printed["zygote"]
    host = printed["zygote"]
    assert isinstance(host, int)
    assert parent_pid(host) == printed["kernel"], "the host is not the kernel's own child"
    assert os.getpgid(host) == host, "the host has no process group of its own for killpg"
    urls = printed["urls"]
    assert isinstance(urls, dict)
    light = DeviceClient(urls["kitchen_light"], TOKEN, 5.0, "kitchen_light")
    await light.call("turn_on")
    assert (await light.get_state())["on"] is True


async def test_a_killed_forked_host_is_reaped_and_restarted_as_a_spawned_host(
    data_dir: Path, kernel: tuple[subprocess.Popen[str], dict[str, object]]
) -> None:
    _, printed = kernel
    forked = printed["zygote"]
    assert isinstance(forked, int)
    os.kill(forked, signal.SIGKILL)
    await eventually(
        lambda: (
            host_pids(data_dir)["kitchen_light"] not in (None, forked) and statuses(data_dir) == {"healthy"}
        )
    )
    assert not pid_alive(forked), "the kernel did not reap its killed host (a zombie is left)"
    restarted = host_pids(data_dir)["kitchen_light"]
    assert isinstance(restarted, int)
    assert "-m rosaos.devices.host" in command_line(restarted)
    assert parent_pid(restarted) == printed["kernel"]
    urls = printed["urls"]
    assert isinstance(urls, dict)
    lamp = DeviceClient(urls["desk_lamp"], TOKEN, 5.0, "desk_lamp")  # the same port again
    await lamp.call("turn_off")
    assert (await lamp.get_state())["on"] is False


async def test_a_killed_kernel_ends_its_forked_host(
    data_dir: Path, kernel: tuple[subprocess.Popen[str], dict[str, object]]
) -> None:
    process, printed = kernel
    host = printed["zygote"]
    assert isinstance(host, int) and pid_alive(host)
    process.kill()
    process.communicate(timeout=30)  # EOF at once: the host does not hold the kernel's stdout
    await eventually(lambda: not pid_alive(host), within=30)


def test_an_unused_zygote_ends_with_its_kernel() -> None:
    script = "from rosaos.devices import host_zygote; print(host_zygote.prefork().pid, flush=True); input()"
    kernel = subprocess.Popen(
        [sys.executable, "-c", script], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    assert kernel.stdout is not None
    zygote = int(kernel.stdout.readline())
    assert running(zygote)
    kernel.kill()
    kernel.communicate(timeout=30)
    deadline = time.monotonic() + 30
    while running(zygote):  # not our child: exited is enough, whoever reaps it
        assert time.monotonic() < deadline, "the zygote outlived its kernel"
        time.sleep(0.05)


def running(pid: int) -> bool:
    """Whether ``pid`` exists and has not exited (a zombie, exited but not yet reaped, has)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return False
    return state not in ("Z", "X")
