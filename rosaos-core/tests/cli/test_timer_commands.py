"""``rosaos ps --timers`` and ``rosaos kill --timer`` on a data directory whose kernel is stopped.

(With a running kernel they use ``GET /timers`` and ``DELETE /timers/{id}``; the real-server
test ``tests/test_timers_after_kernel_kill.py`` and the API tests cover those.)
"""

from __future__ import annotations

import asyncio
import json
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

from rosaos.kernel.event_store import EventStore
from rosaos.timers.timer_book import TimerBook
from rosaos.timers.timer_commands import cancel_timer_command, timers_command


def stopped_kernel_with_a_timer(tmp_path: Path) -> Path:
    config = tmp_path / "rosaos.toml"
    config.write_text(f'data_dir = "{tmp_path / "data"}"\n')

    async def seed() -> None:
        store = await EventStore.open(tmp_path / "data" / "kernel.sqlite3")
        book = await TimerBook.open(store)
        await book.set("turn off the kitchen light", datetime.now(UTC) + timedelta(minutes=10))
        await store.close()

    asyncio.run(seed())
    return config


def test_the_timers_of_a_stopped_kernel_are_listed_and_cancelled(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = stopped_kernel_with_a_timer(tmp_path)
    assert timers_command(config, None, json_output=True, include_settled=False) == 0
    [timer] = json.loads(capsys.readouterr().out)["timers"]
    assert (timer["id"], timer["state"], timer["action"]) == (1, "pending", "turn off the kitchen light")

    assert cancel_timer_command(config, None, 1, json_output=False) == 0
    assert "timer 1: cancelled (turn off the kitchen light)" in capsys.readouterr().out
    assert cancel_timer_command(config, None, 1, json_output=False) == 2
    assert "was already cancelled" in capsys.readouterr().err
    assert timers_command(config, None, json_output=False, include_settled=False) == 0
    assert capsys.readouterr().out.strip() == "no pending timers"


def test_no_event_store_says_to_start_rosaos(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    config = tmp_path / "rosaos.toml"
    config.write_text(f'data_dir = "{tmp_path / "empty"}"\n')
    assert timers_command(config, None, json_output=False, include_settled=True) == 2
    assert "start `rosaos up`" in capsys.readouterr().err
