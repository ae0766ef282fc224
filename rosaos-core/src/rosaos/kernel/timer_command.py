"""``rosaos ps --timers`` and ``rosaos kill --timer ID``: the running kernel's timers from the shell."""

from __future__ import annotations

import asyncio
import json
import sys
from datetime import datetime
from pathlib import Path
from typing import Any

from rich.table import Table

from rosaos.config import ConfigError
from rosaos.frontends.console import console as terminal
from rosaos.kernel.client import KernelUnavailable
from rosaos.kernel.commands import EXIT_CONFIG, _client
from rosaos.kernel.timer_text import clock_text, duration_text


def timers_command(
    config_path: Path | None, url: str | None, json_output: bool, include_settled: bool
) -> int:
    """Print the pending timers (with ``include_settled``, recent fired and cancelled ones too)."""

    async def run() -> dict[str, Any]:
        async with _client(config_path, url) as client:
            params = {"all": "true"} if include_settled else {}
            result: dict[str, Any] = await client.request("GET", "/timers", params=params)
            return result

    try:
        listing = asyncio.run(run())
    except (KernelUnavailable, ConfigError) as error:
        print(f"rosaos ps --timers: {error}", file=sys.stderr)
        return EXIT_CONFIG
    if json_output:
        print(json.dumps(listing, indent=2))
        return 0
    timers = listing["timers"]
    if not timers:
        print("no timers" if include_settled else "no pending timers")
        return 0
    now = datetime.fromisoformat(listing["now"])
    table = Table("id", "state", "due", "in", "action")
    for timer in timers:
        due = datetime.fromisoformat(timer["due"])
        left = (due - now).total_seconds()
        table.add_row(
            str(timer["id"]),
            timer["state"],
            clock_text(due, now),
            duration_text(left) if left > 0 and timer["state"] == "pending" else "",
            timer["action"][:60],
        )
    terminal().print(table)
    return 0


def cancel_timer_command(config_path: Path | None, url: str | None, timer_id: int, json_output: bool) -> int:
    """Cancel one pending timer so it never fires."""

    async def run() -> dict[str, Any]:
        async with _client(config_path, url) as client:
            result: dict[str, Any] = await client.request("DELETE", f"/timers/{timer_id}")
            return result

    try:
        timer = asyncio.run(run())
    except (KernelUnavailable, ConfigError) as error:
        print(f"rosaos kill --timer: {error}", file=sys.stderr)
        return EXIT_CONFIG
    if json_output:
        print(json.dumps(timer, indent=2))
    else:
        print(f"timer {timer['id']}: cancelled ({timer['action']}); it will not run")
    return 0
