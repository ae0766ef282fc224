"""Helpers the cross-package kernel tests share: a kernel on loopback, its API, polling, device state."""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from pathlib import Path
from typing import Any

import httpx

from rosaos.config import load_config
from rosaos.devices.client import DeviceClient
from rosaos.devices.world import build_world
from rosaos.kernel.runtime import Kernel
from rosaos.models.select import ModelSpec
from rosaos.plugins import load_drivers


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
