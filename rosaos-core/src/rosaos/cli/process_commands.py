"""``rosaos ps``, ``rosaos kill`` and ``rosaos estop``: the running kernel's processes, from a shell."""

from __future__ import annotations

import asyncio
import json
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from rich.table import Table

from rosaos.cli.console import console as terminal
from rosaos.cli.up_command import EXIT_CONFIG
from rosaos.config import ConfigError, load_config
from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable


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
