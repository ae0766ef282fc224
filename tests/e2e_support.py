"""Helpers the cross-package kernel tests share: a kernel on loopback (in this process, or ``rosaos up``
as a subprocess to kill), device hosts served on their own, the kernel's API, polling, device state."""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
import subprocess
import time
from collections.abc import AsyncIterator, Awaitable, Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx

from rosaos.auth import load_or_create_token
from rosaos.config import load_config
from rosaos.devices.client import DeviceClient
from rosaos.devices.world import build_world
from rosaos.kernel.runtime import Kernel
from rosaos.models.select import ModelSpec
from rosaos.plugins import load_drivers

from .cli_process import ROSAOS, line_matching


async def eventually(check: Callable[[], Awaitable[Any]], timeout: float = 30.0) -> Any:
    """Poll ``check`` until it returns something truthy; fail with the last value after ``timeout``."""
    deadline = time.monotonic() + timeout
    value = None
    while time.monotonic() < deadline:
        value = await check()
        if value:
            return value
        await asyncio.sleep(0.05)
    raise AssertionError(f"condition not met within {timeout} s (last value: {value!r})")


@contextlib.asynccontextmanager
async def running_kernel(home: Path, world: str, **options: Any) -> AsyncIterator[Kernel]:
    """A kernel on 127.0.0.1:0 whose rosaos.toml is ``world`` with its data in ``home/data``."""
    (home / "rosaos.toml").write_text(f'data_dir = "{home / "data"}"\n' + world)
    config = load_config(home / "rosaos.toml")
    kernel = Kernel(config, build_world(config, load_drivers()), **options)
    await kernel.start(port=0)
    try:
        # "Up" does not wait for background devices (the Reachy simulator); these tests use them.
        await kernel.devices_settled()
        yield kernel
    finally:
        await kernel.stop()


HERE = Path(__file__).parent

TWO_LIGHTS = """
[devices.kitchen_light]
driver = "tapo"
description = "Ceiling light in the kitchen"
sim = { on = false }

[devices.living_room_lamp]
driver = "tapo"
description = "Floor lamp in the living room"
sim = { on = true, brightness = 60 }
"""
"""Two Tapo simulators: the world of the scripted-model kernel tests."""


@contextlib.asynccontextmanager
async def scripted_kernel(home: Path, world: str = TWO_LIGHTS) -> AsyncIterator[Kernel]:
    """A kernel whose kernel and process models are the scripted ``FunctionModel``s of
    ``kernel_scripts.py`` (the workers import it from this folder)."""
    from .kernel_scripts import kernel_model

    async with running_kernel(
        home,
        world,
        kernel_model=kernel_model(),
        process_model=ModelSpec(model="python:kernel_scripts:worker_model"),
        worker_env={"PYTHONPATH": str(HERE)},
    ) as kernel:
        yield kernel


@contextlib.asynccontextmanager
async def kernel_api(kernel: Kernel) -> AsyncIterator[httpx.AsyncClient]:
    """An HTTP client for the kernel's API, with its token."""
    headers = {"Authorization": f"Bearer {kernel.token}"}
    async with httpx.AsyncClient(base_url=kernel.url, headers=headers, timeout=10) as client:
        yield client


async def device_state(kernel: Kernel, name: str) -> dict[str, Any]:
    """``get_state`` of one of the kernel's devices, over MCP HTTP."""
    endpoint = kernel.endpoints()[name]
    assert endpoint.url is not None
    return await DeviceClient(endpoint.url, endpoint.token, 10, name).get_state()


# --- rosaos up and rosaos serve-device as subprocesses, killed as a crash would kill them ----------


def rosaos(*args: str) -> subprocess.Popen[str]:
    """``rosaos ARGS`` as a subprocess, its stderr on its stdout (read it with ``line_matching``)."""
    return subprocess.Popen(
        [str(ROSAOS), *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        env={**os.environ, "COLUMNS": "200"},
    )


def end(process: subprocess.Popen[str], how: signal.Signals = signal.SIGINT, timeout: float = 60) -> None:
    """Send ``how`` (SIGKILL: a crash; SIGINT: Ctrl-C) and wait; SIGKILL if it outlives ``timeout``."""
    process.send_signal(how)
    try:
        process.wait(timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()


READY_WAIT = 120.0
"""How long a kernel may take to be ready after its banner on a busy two-core machine: the first
start imports the fork server's modules (seconds of CPU); a restart adopts the parked one."""


@dataclass
class KernelProcess:
    """A ``rosaos up`` subprocess: its URL, its token and an API client to reach it."""

    process: subprocess.Popen[str]
    url: str
    token: str

    def api(self, timeout: float = 10) -> httpx.Client:
        return httpx.Client(
            base_url=self.url, headers={"Authorization": f"Bearer {self.token}"}, timeout=timeout
        )

    def wait_ready(self, timeout: float = READY_WAIT) -> dict[str, Any]:
        """Wait until ``GET /health`` says ready (devices started, workers warm); return it."""
        health: dict[str, Any] = {}
        deadline = time.monotonic() + timeout
        with self.api() as api:
            while time.monotonic() < deadline:
                health = api.get("/health").json()
                if health["ready"] or health["pool"] == "failed":
                    break
                time.sleep(0.05)
        assert health.get("ready"), f"the kernel was not ready within {timeout} s: {health}"
        return health

    def kill(self) -> None:
        """SIGKILL: the kernel dies as in a crash, with no shutdown at all."""
        end(self.process, signal.SIGKILL)

    def stop(self) -> None:
        """Ctrl-C: the kernel's own shutdown."""
        end(self.process, signal.SIGINT)


def start_kernel(config: Path, *, ready: bool = True) -> KernelProcess:
    """``rosaos up --config CONFIG --port 0``, once its banner is out (and, with ``ready``, once
    ``GET /health`` says ready). The caller ends it with :meth:`KernelProcess.kill` or ``stop``."""
    process = rosaos("up", "--config", str(config), "--port", "0")
    url = line_matching(process, r"rosaOS is up at (http://\S+?)/?$").group(1)
    kernel = KernelProcess(process, url, load_or_create_token(load_config(config).data_dir))
    if ready:
        try:
            kernel.wait_ready()
        except BaseException:
            kernel.kill()
            raise
    return kernel


@contextlib.contextmanager
def served_device(home: Path, name: str, table: str) -> Iterator[tuple[str, str]]:
    """``rosaos serve-device NAME`` with ``[devices.NAME]`` = ``table``, its data in ``home/NAME-data``,
    as on a robot's own computer (it outlives any kernel); yields its MCP URL and token."""
    config = home / f"{name}.toml"
    config.write_text(f'data_dir = "{home / f"{name}-data"}"\n[devices.{name}]\n{table}')
    served = rosaos("serve-device", name, "--config", str(config), "--port", "0")
    try:
        url = line_matching(served, r"(http://127\.0\.0\.1:\d+/mcp)").group(1)
        yield url, (home / f"{name}-data" / "token").read_text().strip()
    finally:
        end(served, signal.SIGINT, timeout=30)


DOG = 'driver = "ros"\nprofile = "puppypi"\ndescription = "Hiwonder PuppyPi robot dog"\n'
"""The robot dog on the rosbridge simulator, as a ``[devices.dog]`` table for :func:`served_device`."""


def remote_device(name: str, url: str, token: str, description: str, driver: str = "ros") -> str:
    """A ``[devices.NAME]`` table for a kernel that reaches a device served elsewhere."""
    return (
        f'[devices.{name}]\ndriver = "{driver}"\nurl = "{url}"\ntoken = "{token}"\n'
        f'description = "{description}"\n'
    )


# --- talking to an in-process kernel's API, and the walking dog of the stop tests --------------------


async def chat(api: httpx.AsyncClient, text: str) -> int:
    """``POST /chat``; the event's id."""
    response = await api.post("/chat", json={"text": text})
    assert response.status_code == 202, response.text
    return int(response.json()["id"])


async def handled(api: httpx.AsyncClient, event_id: int) -> bool:
    return bool((await api.get(f"/events/{event_id}")).json().get("handled"))


async def updates_of(api: httpx.AsyncClient, event_id: int) -> list[dict[str, Any]]:
    """The updates that event ``event_id`` caused (its replies, tool calls, notices)."""
    updates = (await api.get("/updates", params={"after": 0, "limit": 1000})).json()["updates"]
    return [u for u in updates if u.get("event_id") == event_id]


async def all_healthy(api: httpx.AsyncClient) -> bool:
    return all(device["status"] == "healthy" for device in (await api.get("/devices")).json())


async def walk_the_dog(
    api: httpx.AsyncClient, kernel: Kernel, command: str, timeout: float = 120
) -> dict[str, Any]:
    """Say ``command``; return the process that holds the dog once the dog is moving."""
    await chat(api, command)

    async def walking() -> dict[str, Any] | None:
        running = [p for p in (await api.get("/processes")).json() if "dog" in p["devices"]]
        if running and abs((await device_state(kernel, "dog"))["linear"]) > 0.01:
            return running[0]
        return None

    walk: dict[str, Any] = await eventually(walking, timeout=timeout)
    return walk
