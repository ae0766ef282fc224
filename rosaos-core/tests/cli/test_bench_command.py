"""``rosaos bench`` end to end: a small task file through the real CLI, the kernel, workers and simulators.

One run (module fixture) of a desk world (a Tapo lamp, Spotify, and a drone whose driver is not
installed) with five tasks: two that must pass, a conversation (two sentences, the second 1.5 s later), one whose ``expect`` is wrong on purpose (it must
fail, and the run goes on), one that needs the drone (pending, not a failure). The tests read
its JSON.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pytest
from rich.console import Console
from typer.testing import CliRunner

from rosaos.bench.report import print_report
from rosaos.bench.results import BenchResult, Summary
from rosaos.cli import app, bench_command

pytestmark = pytest.mark.slow

DESK = """\
name: desk
world:
  lamp:
    driver: tapo
    description: Smart lamp on the desk
    state: {on: false, brightness: 100, hue: 0, saturation: 0, color_temp: 4000}
  spotify:
    driver: spotify
    description: Music on the desk speaker
    state: {is_playing: false, volume: 40, track: null, shuffle: false, repeat: "off"}
    sim:
      catalog:
        - {track: So What, artist: Miles Davis, album: Kind of Blue, genre: jazz}
        - {track: Here Comes the Sun, artist: The Beatles, album: Abbey Road, genre: rock}
  drone:
    driver: drone
    state: {altitude: 0}
tasks:
  - id: desk-lamp-on
    say: Turn on the lamp
    expect: {lamp: {on: true}}
    reply: "(?i)lamp"
  - id: desk-jazz
    say: Play some jazz
    expect: {spotify: {is_playing: true, track: {contains: so what}}}
  - id: desk-wrong-expectation
    say: Turn on the lamp
    expect: {lamp: {on: true, brightness: 50}}
  - id: desk-conversation
    say:
      - Turn on the lamp
      - {after: 1.5, text: Play some jazz}
    settle: 30
    expect:
      lamp: {on: true}
      spotify: {is_playing: true, track: {contains: so what}}
  - id: desk-drone-up
    say: Tell the drone to take off
    expect: {drone: {altitude: {gt: 1}}}
"""


def rosaos_command() -> list[str]:
    """The installed ``rosaos`` script next to this Python, as a user runs it."""
    script = Path(sys.executable).with_name("rosaos")
    return [str(script)] if script.exists() else [sys.executable, "-m", "rosaos.cli"]


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """``rosaos bench desk.yaml --json --out result.json`` once, with its own data dir and no user config."""
    home = tmp_path_factory.mktemp("bench-run")
    tasks = home / "desk.yaml"
    tasks.write_text(DESK, encoding="utf-8")
    env = {
        **{k: v for k, v in os.environ.items() if not k.startswith("ROSAOS_")},
        "ROSAOS_DATA_DIR": str(home / "data"),
        "ROSAOS_KERNEL__POOL_SIZE": "1",  # one warm worker: the tasks run one at a time anyway
        "XDG_CONFIG_HOME": str(home / "config"),
        "XDG_DATA_HOME": str(home / "share"),
    }
    done = subprocess.run(
        [*rosaos_command(), "bench", str(tasks), "--json", "--out", str(home / "result.json")],
        capture_output=True,
        text=True,
        env=env,
        cwd=home,
        timeout=240,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    return {
        "json": json.loads(done.stdout),
        "out": json.loads((home / "result.json").read_text(encoding="utf-8")),
        "data": home / "data",
    }


def task(run: dict[str, Any], task_id: str) -> dict[str, Any]:
    [found] = [t for f in run["json"]["files"] for t in f["tasks"] if t["id"] == task_id]
    return found


def test_a_command_that_does_what_it_says_passes(run: dict[str, Any]) -> None:
    [trial] = task(run, "desk-lamp-on")["trials"]
    assert trial["status"] == "pass", trial
    assert trial["reply_ok"] is True
    assert trial["latency_s"] > 0
    # At least the kernel's turn on the sentence (an offline plan runs without a model request).
    assert trial["model_calls"] >= 1
    assert trial["tool_calls"] >= 2  # launch_process, then the lamp's turn_on


def test_music_plays_from_the_task_files_catalog(run: dict[str, Any]) -> None:
    [trial] = task(run, "desk-jazz")["trials"]
    assert trial["status"] == "pass", trial


def test_a_conversation_posts_each_item_after_its_delay_and_settles_after_the_last(
    run: dict[str, Any],
) -> None:
    conversation = task(run, "desk-conversation")
    [trial] = conversation["trials"]
    assert trial["status"] == "pass", trial
    assert trial["processes"] == 2
    assert trial["latency_s"] >= 1.5  # measured from the first post: includes the wait
    assert conversation["say"] == "Turn on the lamp / Play some jazz"


def test_a_wrong_expectation_fails_with_the_differing_key(run: dict[str, Any]) -> None:
    [trial] = task(run, "desk-wrong-expectation")["trials"]
    assert trial["status"] == "fail"
    assert [(d["device"], d["key"], d["expected"], d["actual"]) for d in trial["differences"]] == [
        ("lamp", "brightness", 50, 100)
    ]
    assert trial["reason"] == "lamp.brightness: expected 50, got 100"


def test_a_task_for_a_driver_that_is_not_installed_is_pending_not_failed(run: dict[str, Any]) -> None:
    pending = task(run, "desk-drone-up")
    assert pending["pending"].startswith("drone: driver 'drone' not installed (installed: ")
    assert pending["trials"] == []


def test_the_summary_leaves_pending_tasks_out(run: dict[str, Any]) -> None:
    summary = run["json"]["summary"]
    assert (summary["tasks"], summary["passed"], summary["pending"]) == (4, 3, 1)
    assert summary["success_rate"] == pytest.approx(3 / 4)
    assert summary["latency_p50_s"] <= summary["latency_p95_s"]
    assert summary["pass_hat_k"] == {"1": pytest.approx(3 / 4)}


def test_out_writes_the_same_result(run: dict[str, Any]) -> None:
    assert run["out"] == run["json"]


def test_the_run_stays_in_the_data_dir_it_was_given(run: dict[str, Any]) -> None:
    assert Path(run["json"]["data_dir"]).parent == run["data"] / "bench"


def test_the_table_shows_result_differences_and_pending(run: dict[str, Any]) -> None:
    console = Console(width=200, record=True)
    print_report(BenchResult.model_validate(run["json"]), console)
    text = console.export_text()
    assert "desk-wrong-expectation │ fail" in text
    assert "lamp.brightness: 50 vs 100" in text
    assert "desk-drone-up          │ pending" in text
    assert "Overall: 3/4 passed (75.0%) · 1 pending (not counted)" in text


# --- usage errors and the exit code (in-process: nothing runs) ----------------------------------


def test_no_path_says_what_to_pass() -> None:
    result = CliRunner().invoke(app, ["bench"])
    assert result.exit_code == 2
    assert "pass a file or a directory of them, e.g. `rosaos bench ../shared/bench/tasks`" in result.output


def test_a_bad_task_file_is_a_usage_error_naming_file_and_key(tmp_path: Path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(DESK.replace("    expect: {lamp: {on: true}}\n", "", 1), encoding="utf-8")
    result = CliRunner().invoke(app, ["bench", str(bad)])
    assert result.exit_code == 2
    assert f"{bad}: tasks[0] (desk-lamp-on).expect: Field required" in result.output


def test_a_pattern_that_matches_no_task_is_a_usage_error(tmp_path: Path) -> None:
    tasks = tmp_path / "desk.yaml"
    tasks.write_text(DESK, encoding="utf-8")
    result = CliRunner().invoke(app, ["bench", str(tasks), "--tasks", "kitchen-*"])
    assert result.exit_code == 2
    assert "no task id matches --tasks kitchen-*" in result.output


def test_an_unusable_model_is_a_usage_error(tmp_path: Path) -> None:
    tasks = tmp_path / "desk.yaml"
    tasks.write_text(DESK, encoding="utf-8")
    result = CliRunner().invoke(app, ["bench", str(tasks), "--model", "openai-compatible"])
    assert result.exit_code == 2
    assert "needs base_url and model_name" in result.output


@pytest.mark.parametrize(("fail_under", "exit_code"), [(None, 0), (0.5, 0), (0.9, 1)])
def test_failures_exit_zero_unless_below_fail_under(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fail_under: float | None, exit_code: int
) -> None:
    async def two_of_three(*args: Any, **kwargs: Any) -> BenchResult:
        summary = Summary(
            tasks=3, pending=0, trials=3, passed=2, success_rate=2 / 3, latency_p50_s=None, latency_p95_s=None
        )
        return BenchResult(
            model="test",
            repeat=1,
            started_at=datetime.now(UTC),
            duration_s=0,
            data_dir="-",
            files=[],
            summary=summary,
        )

    monkeypatch.setattr(bench_command, "run_bench", two_of_three)
    tasks = tmp_path / "desk.yaml"
    tasks.write_text(DESK, encoding="utf-8")
    args = ["bench", str(tasks), "--json"] + (["--fail-under", str(fail_under)] if fail_under else [])
    assert CliRunner().invoke(app, args).exit_code == exit_code
