"""``rosaos log``: the activity log, as a table or as JSON.

From the running kernel of the data directory (``GET /activity``), else straight from the data
directory's event store, so the log of a stopped kernel or of ``rosaos bench`` runs stays readable.
"""

from __future__ import annotations

import asyncio
import json
import re
import sys
import time
from datetime import datetime
from pathlib import Path
from typing import Any

from rich.table import Table

from rosaos.cli.console import console as terminal
from rosaos.config import ConfigError, load_config
from rosaos.kernel.activity import ActivityLog
from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable, running_kernel_url
from rosaos.kernel.database import Database

EXIT_CONFIG = 2
EVENTS_FILE = "kernel.sqlite3"
"""The event store's file in the data directory (as the kernel runtime names it)."""
_DURATION = re.compile(r"^(?P<amount>\d+(?:\.\d+)?)\s*(?P<unit>s|m|h|d)$")
_UNIT_SECONDS = {"s": 1, "m": 60, "h": 3600, "d": 86400}


def parse_since(text: str, now: float | None = None) -> float:
    """``10m``, ``2h``, ``1d``, ``30s`` ago, or an ISO 8601 time, as epoch seconds.

    Raises ``ValueError`` naming the accepted forms.
    """
    now = time.time() if now is None else now
    found = _DURATION.match(text.strip())
    if found:
        return now - float(found.group("amount")) * _UNIT_SECONDS[found.group("unit")]
    try:
        moment = datetime.fromisoformat(text.strip())
    except ValueError:
        raise ValueError(
            f"--since {text!r}: give a duration ago (30s, 10m, 2h, 1d) or an ISO time (2026-05-01T14:00)"
        ) from None
    return moment.timestamp()


async def read_stored(path: Path, params: dict[str, Any]) -> list[dict[str, Any]]:
    """The log straight from a data directory's event store, when no kernel is running there
    (after ``rosaos bench``, or with the kernel stopped)."""
    if not await asyncio.to_thread(path.is_file):
        raise FileNotFoundError(
            f"no kernel is running and there is no event store at {path}; start `rosaos up`"
        )
    database = await Database.open(path)
    try:
        log = await ActivityLog.open(database)
        entries = await log.query(
            device=params.get("device"),
            process_id=params.get("process"),
            since=params.get("since"),
            limit=int(params["limit"]),
        )
    finally:
        await database.close()
    return [entry.model_dump(mode="json") for entry in entries]


def log_command(
    config_path: Path | None,
    url: str | None,
    device: str | None,
    process: int | None,
    since: str | None,
    limit: int,
    json_output: bool,
) -> int:
    """Print the activity log, filtered."""
    params: dict[str, Any] = {"limit": limit}
    try:
        if since is not None:
            params["since"] = parse_since(since)
    except ValueError as error:
        print(f"rosaos log: {error}", file=sys.stderr)
        return EXIT_CONFIG
    if device is not None:
        params["device"] = device
    if process is not None:
        params["process"] = process

    async def run() -> list[dict[str, Any]]:
        config = load_config(config_path)
        if url is None and running_kernel_url(config.data_dir) is None:
            return await read_stored(config.data_dir / EVENTS_FILE, params)
        async with KernelClient.from_config(config, url=url) as client:
            page: dict[str, Any] = await client.request("GET", "/activity", params=params)
            return list(page["entries"])

    try:
        entries = asyncio.run(run())
    except (KernelUnavailable, ConfigError, FileNotFoundError) as error:
        print(f"rosaos log: {error}", file=sys.stderr)
        return EXIT_CONFIG
    if json_output:
        print(json.dumps(entries, indent=2))
        return 0
    if not entries:
        print("no tool calls logged" + (" for these filters" if len(params) > 1 else ""))
        return 0
    table = Table("time", "process", "device", "tool", "arguments", "outcome", "safety", "seconds")
    for entry in entries:
        safety = entry.get("safety") or {}
        table.add_row(
            datetime.fromtimestamp(entry["started"]).strftime("%H:%M:%S"),
            str(entry["process_id"]),
            entry["device"],
            entry["tool"],
            json.dumps(entry["arguments"])[:60],
            "ok" if entry["ok"] else f"error: {(entry['error'] or '')[:60]}",
            safety.get("decision", ""),
            f"{entry['duration']:.2f}",
        )
    terminal().print(table)
    return 0
