"""``rosaos ps --timers`` and ``rosaos kill --timer ID``: the kernel's timers from the shell.

They ask the running kernel of the data directory (``GET /timers``, ``DELETE /timers/{id}``),
else read and change the data directory's event store directly: the timers of a stopped
kernel fire when it starts again, so they stay listable and cancellable meanwhile.
"""

from __future__ import annotations

import asyncio
import json
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from rich.table import Table

from rosaos.cli.console import console as terminal
from rosaos.cli.log_command import EVENTS_FILE
from rosaos.cli.up_command import EXIT_CONFIG
from rosaos.config import ConfigError, load_config
from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable, running_kernel_url
from rosaos.kernel.event_store import EventStore
from rosaos.timers.timer_book import TimerBook, TimerError
from rosaos.timers.timer_phrases import duration_text
from rosaos.timers.timer_text import clock_text


async def _stored_book(path: Path) -> tuple[EventStore, TimerBook]:
    """The timers of a data directory whose kernel is not running."""
    if not await asyncio.to_thread(path.is_file):
        raise FileNotFoundError(
            f"no kernel is running and there is no event store at {path}; start `rosaos up`"
        )
    store = await EventStore.open(path)
    return store, await TimerBook.open(store)


def timers_command(
    config_path: Path | None, url: str | None, json_output: bool, include_settled: bool
) -> int:
    """Print the pending timers (with ``include_settled``, recent fired and cancelled ones too)."""

    async def run() -> dict[str, Any]:
        config = load_config(config_path)
        if url is None and running_kernel_url(config.data_dir) is None:
            store, book = await _stored_book(config.data_dir / EVENTS_FILE)
            try:
                timers = [timer.model_dump(mode="json") for timer in await book.list_timers(include_settled)]
            finally:
                await store.close()
            return {"timers": timers, "now": datetime.now(UTC).isoformat()}
        async with KernelClient.from_config(config, url=url) as client:
            params = {"all": "true"} if include_settled else {}
            result: dict[str, Any] = await client.request("GET", "/timers", params=params)
            return result

    try:
        listing = asyncio.run(run())
    except (KernelUnavailable, ConfigError, FileNotFoundError) as error:
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
        config = load_config(config_path)
        if url is None and running_kernel_url(config.data_dir) is None:
            store, book = await _stored_book(config.data_dir / EVENTS_FILE)
            try:
                return (await book.cancel(timer_id)).model_dump(mode="json")
            except KeyError:
                raise TimerError(f"no timer {timer_id}; `rosaos ps --timers` lists them") from None
            finally:
                await store.close()
        async with KernelClient.from_config(config, url=url) as client:
            result: dict[str, Any] = await client.request("DELETE", f"/timers/{timer_id}")
            return result

    try:
        timer = asyncio.run(run())
    except (KernelUnavailable, ConfigError, FileNotFoundError, TimerError) as error:
        print(f"rosaos kill --timer: {error}", file=sys.stderr)
        return EXIT_CONFIG
    if json_output:
        print(json.dumps(timer, indent=2))
    else:
        print(f"timer {timer['id']}: cancelled ({timer['action']}); it will not run")
    return 0
