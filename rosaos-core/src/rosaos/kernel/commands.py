"""``rosaos up``, ``rosaos ps`` and ``rosaos kill``: run the kernel, and inspect it from a shell."""

from __future__ import annotations

import asyncio
import json
import logging
import signal
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from rosaos.auth import token_path
from rosaos.config import ConfigError, RosaosConfig, load_config
from rosaos.devices.world import build_world
from rosaos.drivers import DeviceError
from rosaos.frontends.console import console as terminal
from rosaos.kernel.client import KernelClient, KernelUnavailable
from rosaos.kernel.runtime import Kernel, KernelError
from rosaos.models.select import ModelError
from rosaos.plugins import load_drivers

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
    try:
        url = await kernel.start()
    except (KernelError, DeviceError, ModelError) as error:
        err.print(f"rosaos up: {error}", markup=False)
        return 1
    try:
        _print_banner(kernel, url, console)
        await stop.wait()
        console.print("Stopping rosaOS…", markup=False)
    finally:
        await kernel.stop()
    console.print("Stopped. Unhandled events stay queued for the next start.", markup=False)
    return 0


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
    for entry in kernel.supervisor.directory().values():
        where = entry.url or "-"
        console.print(f"  Device:    {entry.name:<20} {entry.status:<16} {where}", markup=False)
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


def _client(config_path: Path | None, url: str | None) -> KernelClient:
    return KernelClient.from_config(load_config(config_path), url=url)


def progress_text(progress: dict[str, Any] | None) -> str:
    """A process's latest progress for ``rosaos ps``: "42% looked 3 of 8 ways ...", or ""."""
    if not progress:
        return ""
    total = progress.get("total")
    percent = f"{round(100 * progress['progress'] / total)}% " if total else ""
    return f"{percent}{progress.get('message', '')}"[:70]


def ps_command(config_path: Path | None, url: str | None, json_output: bool, all_processes: bool) -> int:
    """Print the kernel's processes."""

    async def run() -> list[dict[str, Any]]:
        async with _client(config_path, url) as client:
            return await client.processes(include_ended=all_processes)

    try:
        processes = asyncio.run(run())
    except (KernelUnavailable, ConfigError) as error:
        print(f"rosaos ps: {error}", file=sys.stderr)
        return EXIT_CONFIG
    if not all_processes:
        processes = [p for p in processes if p["state"] == "running"]
    if json_output:
        print(json.dumps(processes, indent=2))
        return 0
    if not processes:
        print("no running processes" if not all_processes else "no processes")
        return 0
    table = Table("id", "state", "devices", "age", "task", "progress")
    now = datetime.now(UTC)
    for process in processes:
        started = datetime.fromisoformat(process["started_at"])
        table.add_row(
            str(process["id"]),
            process["state"],
            ", ".join(process["devices"]),
            f"{(now - started).total_seconds():.0f}s",
            process["task"].splitlines()[0][:60],
            progress_text(process.get("progress")),
        )
    terminal().print(table)
    return 0


def estop_command(
    config_path: Path | None, url: str | None, reset: bool, reason: str, json_output: bool
) -> int:
    """Latch (or reset) the emergency stop."""

    async def run() -> dict[str, Any]:
        async with _client(config_path, url) as client:
            return await (client.reset_emergency_stop() if reset else client.emergency_stop(reason))

    try:
        report = asyncio.run(run())
    except (KernelUnavailable, ConfigError) as error:
        print(f"rosaos estop: {error}", file=sys.stderr)
        return EXIT_CONFIG
    if json_output:
        print(json.dumps(report, indent=2))
    elif reset:
        print("emergency stop reset: processes may run again")
    else:
        print(f"EMERGENCY STOP latched: {report['reason']}")
        print(f"  terminated processes: {', '.join(map(str, report['terminated'])) or 'none'}")
        for device in report["devices"]:
            # The safe_stop tool names its device ("kitchen_light: safe stop done"); the line has already.
            detail = str(device["detail"]).removeprefix(f"{device['name']}: ")
            print(f"  {device['name']}: {'safe' if device['ok'] else 'FAILED'}: {detail}")
        if not report.get("saved", True):
            print(
                "  WARNING: the latch could not be saved (see the kernel log): a kernel restart would clear it"
            )
        print("Reset with `rosaos estop --reset` once it is safe.")
    return 0 if reset or (report.get("saved", True) and all(d["ok"] for d in report["devices"])) else 1


def kill_command(config_path: Path | None, url: str | None, process_id: int, json_output: bool) -> int:
    """Terminate one process; its leases are released."""

    async def run() -> dict[str, Any]:
        async with _client(config_path, url) as client:
            return await client.terminate(process_id)

    try:
        process = asyncio.run(run())
    except (KernelUnavailable, ConfigError) as error:
        print(f"rosaos kill: {error}", file=sys.stderr)
        return EXIT_CONFIG
    if json_output:
        print(json.dumps(process, indent=2))
    else:
        print(
            f"process {process['id']}: {process['state']}; released {', '.join(process['devices']) or 'nothing'}"
        )
    return 0
