"""``rosaos up``: start the devices, the kernel, the worker pool and the web page; run until Ctrl-C."""

from __future__ import annotations

import asyncio
import logging
import signal
import time
from pathlib import Path
from typing import Any

from rich.console import Console

from rosaos.auth import token_path
from rosaos.cli.console import console as terminal
from rosaos.cli.up_progress import ONE_LINE_EACH, device_line, report_devices
from rosaos.config import ConfigError, RosaosConfig, load_config
from rosaos.devices import host_zygote
from rosaos.devices.world import build_world
from rosaos.drivers import DeviceError
from rosaos.kernel.runtime import Kernel, KernelError
from rosaos.models.select import ModelError
from rosaos.plugins import load_drivers
from rosaos.processes.zygote import prefork

EXIT_CONFIG = 2


def model_overrides(
    model: str | None, process_model: str | None, base_url: str | None, model_name: str | None
) -> dict[str, Any]:
    """``--model`` & co. as config overrides for the ``[models]`` table."""
    models: dict[str, Any] = {}
    if model:
        models["kernel"] = model
    if process_model:
        models["process"] = process_model
    if base_url:
        models["base_url"] = base_url
    if model_name:
        models["model_name"] = model_name
    return models


def load_for_cli(config_path: Path | None, **overrides: Any) -> RosaosConfig:
    """Load the config; CLI overrides win, merged key by key into their tables (pydantic-settings deep-merges)."""
    return load_config(config_path, **overrides)


def up_command(
    config_path: Path | None,
    *,
    host: str | None,
    port: int | None,
    pool_size: int | None,
    models: dict[str, Any],
) -> int:
    """Start devices, kernel, pool and web page; run until Ctrl-C."""
    console = terminal()
    err = terminal(stderr=True)
    kernel_overrides: dict[str, Any] = {}
    if host is not None:
        kernel_overrides["host"] = host
    if port is not None:
        kernel_overrides["port"] = port
    if pool_size is not None:
        kernel_overrides["pool_size"] = pool_size
    overrides: dict[str, Any] = {}
    if kernel_overrides:
        overrides["kernel"] = kernel_overrides
    if models:
        overrides["models"] = models
    try:
        config = load_for_cli(config_path, **overrides)
        registry = load_drivers()
        world = build_world(config, registry)
        # Now, with the kernel's modules imported and before any thread or file: the first device
        # host and the fork server then share their memory with the kernel (see
        # rosaos.devices.host_zygote and rosaos.processes.zygote).
        host_zygote.prefork()
        if config.kernel.fork_server:
            prefork()
        kernel = Kernel(config, world)
    except (ConfigError, ModelError) as error:
        err.print(f"rosaos up: {error}", markup=False)
        return EXIT_CONFIG
    for broken in registry.broken:
        err.print(
            f"warning: plugin {broken.plugin} ({broken.package}) is broken: {broken.error}", markup=False
        )
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    # The MCP HTTP clients log every request at INFO; health checks would flood the console.
    for noisy in ("httpx", "httpx2", "mcp", "fastmcp"):
        logging.getLogger(noisy).setLevel(logging.WARNING)
    return asyncio.run(_serve(kernel, console, err))


async def _serve(kernel: Kernel, console: Console, err: Console) -> int:
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for signum in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(signum, stop.set)
    count = len(kernel.world)
    console.print(f"Starting rosaOS with {count} device{'' if count == 1 else 's'}…", markup=False)
    started = time.monotonic()
    try:
        # The banner does not wait for every device: a hundred lamps take seconds, and a command
        # to one still starting waits for it. They are reported below as they come up.
        url = await kernel.start(wait_for_devices=False)
    except (KernelError, DeviceError, ModelError) as error:
        err.print(f"rosaos up: {error}", markup=False)
        return 1
    progress: asyncio.Task[None] | None = None
    ready: asyncio.Task[None] | None = None
    try:
        _print_banner(kernel, url, console)
        progress = asyncio.create_task(report_devices(kernel.supervisor.directory, console, started))
        ready = asyncio.create_task(_say_when_ready(kernel, console, started))
        if await _stopped_or_pool_failed(stop, kernel.manager.warming):
            console.print("Stopping rosaOS…", markup=False)
        else:
            return 1
    finally:
        for task in (progress, ready):
            if task is not None:
                task.cancel()
        await kernel.stop()
        host_zygote.discard()  # a world with no local device never used it
    console.print("Stopped. Unhandled events stay queued for the next start.", markup=False)
    return 0


async def _say_when_ready(kernel: Kernel, console: Console, started: float) -> None:
    """One line once every device has had its first start and the workers are warm (the banner
    comes before both); `rosaos ready` and ``GET /health`` tell scripts the same."""
    while not (readiness := kernel.readiness()).ready:
        if readiness.pool == "failed":
            return
        await asyncio.sleep(0.1)
    console.print(f"rosaOS is ready ({time.monotonic() - started:.1f} s after start).", markup=False)


async def _stopped_or_pool_failed(stop: asyncio.Event, warming: asyncio.Task[None] | None) -> bool:
    """Wait for Ctrl-C; False (after saying why) if the worker pool, still starting at the banner,
    cannot start: nothing could run then."""
    stopping = asyncio.create_task(stop.wait())
    waiting: set[asyncio.Future[Any]] = {stopping, *([warming] if warming is not None else [])}
    while not stopping.done():
        done, waiting = await asyncio.wait(waiting, return_when=asyncio.FIRST_COMPLETED)
        if warming in done and not warming.cancelled() and warming.exception() is not None:
            stopping.cancel()
            terminal(stderr=True).print(f"rosaos up: {warming.exception()}", markup=False)
            return False
    return True


def _print_banner(kernel: Kernel, url: str, console: Console) -> None:
    console.print(f"rosaOS is up at {url}/", style="bold green", markup=False)
    console.print(
        f"  Web page:  {kernel.login_link()}   (one-time login link, valid 10 minutes)", markup=False
    )
    console.print(
        f"  Token:     {token_path(kernel.data_dir)}   (bearer token for the API and MCP servers)",
        markup=False,
    )
    console.print(f"  Model:     {kernel.model_description}", markup=False)
    if kernel.model_notice:
        console.print(f"  {kernel.model_notice}", style="yellow", markup=False)
    entries = kernel.supervisor.directory()
    if len(entries) <= ONE_LINE_EACH:
        for entry in entries.values():
            console.print(device_line(entry), markup=False)
    else:
        healthy = sum(1 for entry in entries.values() if entry.status == "healthy")
        console.print(
            f"  Devices:   {healthy} of {len(entries)} healthy so far; the rest are reported as they come up",
            markup=False,
        )
    if latch := kernel.manager.emergency_stop:
        since = latch.time.astimezone().strftime("%Y-%m-%d %H:%M:%S")
        console.print(
            f"EMERGENCY STOP is still latched, since {since}: {latch.reason}", style="bold red", markup=False
        )
        console.print(
            "  No process will run until a person resets it: `rosaos estop --reset`, or the web page.",
            style="red",
            markup=False,
        )
    console.print("Chat with `rosaos chat`; stop with Ctrl-C.", markup=False)
