"""Health checks in ``rosaos devices list`` and ``devices check``: start-up and answer budgets.

The ``slowsim`` driver (``slow_sim_driver.py``) is installed through an entry point, as pip
would, so the commands load it like any driver. Its ``sim`` table says how long it takes to
start and to answer. The outcomes are asserted, never the timings.
"""

from __future__ import annotations

import asyncio
import importlib
import json
import os
import pty
import shutil
import subprocess
import time
from collections.abc import Iterator
from io import StringIO
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
from rich.console import Console

from rosaos.auth import load_or_create_token
from rosaos.cli.device_commands import check_device, list_devices, serve_device_command
from rosaos.config import load_config
from rosaos.devices.progress import CheckProgress
from rosaos.devices.run_files import (
    DeviceStatus,
    RunFile,
    RunFileEntry,
    devices_not_ready,
    now,
    run_file_path,
    write_atomic,
)
from rosaos.devices.serve import open_device, serve_http
from rosaos.devices.supervisor import DeviceSupervisor
from rosaos.devices.world import build_world
from rosaos.plugins import load_drivers

from .devices_support import ROSAOS, eventually, write_config

DRIVER_SOURCE = Path(__file__).parent / "slow_sim_driver.py"


def installed_driver() -> ModuleType:
    """The ``slow_sim_driver`` module as ``load_drivers`` imports it: the copy the fixture installed."""
    return importlib.import_module("slow_sim_driver")


@pytest.fixture
def slowsim(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """Install the ``slowsim`` driver the way pip would (the module and a dist-info with its entry
    point, in a site dir of its own); the site dir."""
    site = tmp_path / "site"
    dist = site / "rosaos_test_slowsim-0.1.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: rosaos-test-slowsim\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[rosaos.drivers]\nslowsim = slow_sim_driver\n")
    shutil.copy(DRIVER_SOURCE, site / DRIVER_SOURCE.name)
    monkeypatch.syspath_prepend(str(site))
    assert "slowsim" in load_drivers(allow={"slowsim"}).names
    installed_driver().STARTED.clear()
    yield site
    installed_driver().STARTED.clear()


def slow(name: str, **sim: float) -> str:
    """A ``[devices.NAME]`` table for a slowsim instance with these ``sim`` keys."""
    table = ", ".join(f"{key} = {value}" for key, value in sim.items())
    return f'\n[devices.{name}]\ndriver = "slowsim"\nsim = {{ {table} }}\n'


def listed(capsys: pytest.CaptureFixture[str], config: Path, **options: Any) -> dict[str, dict[str, Any]]:
    """``rosaos devices list --json`` as {instance: row}."""
    assert list_devices(config, json_output=True, **options) == 0
    return {row["instance"]: row for row in json.loads(capsys.readouterr().out)}


def rosaos_up_is_starting(
    data_dir: Path, name: str, status: DeviceStatus = "starting", error: str | None = None
) -> None:
    """Write the run file a running ``rosaos up`` (this test's process) has while starting ``name``."""
    entry = RunFileEntry(url=None, pid=None, status=status, since=now(), error=error)
    runtime = RunFile(supervisor_pid=os.getpid(), devices={name: entry})
    write_atomic(run_file_path(data_dir), runtime.model_dump_json())


# --- start-up and answer budgets ------------------------------------------------------------------


def test_a_simulator_slower_than_the_answer_budget_but_within_the_start_budget_is_healthy(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, slow("lamp", start_seconds=2.5))
    row = listed(capsys, config, timeout=2, start_timeout=30)["lamp"]
    assert (row["health"], row["via"], row["state"]) == (
        "healthy (not served)",
        "in-process",
        {"started_in": 2.5},
    )


@pytest.mark.timeout(60)
def test_a_simulator_that_never_starts_is_reported_with_the_reason_and_the_others_are_not_held_up(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    body = slow("stuck", start_seconds=-1) + slow("fine", start_seconds=0)
    rows = listed(capsys, write_config(tmp_path / "rosaos.toml", data_dir, body), start_timeout=1)
    assert rows["stuck"]["health"] == (
        "error: stuck did not finish starting within 1 s; a slow simulator or a busy machine may need "
        "more (--start-timeout)"
    )
    assert rows["fine"]["health"] == "healthy (not served)"


@pytest.mark.timeout(60)
def test_a_started_device_that_never_answers_is_reported_after_the_answer_budget(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, slow("mute", answer_seconds=-1))
    health = listed(capsys, config, timeout=0.5)["mute"]["health"]
    assert health.startswith("error: mute (in-process) did not answer within 0.5 s")


def test_instances_of_one_driver_start_one_at_a_time(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    body = slow("first", start_seconds=0.3) + slow("second", start_seconds=0.3)
    rows = listed(capsys, write_config(tmp_path / "rosaos.toml", data_dir, body))
    assert {name: row["health"] for name, row in rows.items()} == {
        "first": "healthy (not served)",
        "second": "healthy (not served)",
    }


def test_check_gives_a_slow_simulator_its_start_up_budget(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, slow("lamp", start_seconds=2.5))
    assert check_device("lamp", config, timeout=2, start_timeout=30) == 0
    assert capsys.readouterr().out.startswith("lamp: healthy, checked in this process")


@pytest.mark.timeout(60)
def test_check_of_a_simulator_that_never_starts_fails_with_the_reason(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, slow("stuck", start_seconds=-1))
    assert check_device("stuck", config, json_output=True, start_timeout=1) == 1
    report = json.loads(capsys.readouterr().out)
    assert (report["ok"], report["via"]) == (False, "in-process")
    assert report["error"].startswith("stuck did not finish starting within 1 s")


# --- instances that rosaos up is starting ---------------------------------------------------------


def test_list_waits_for_rosaos_up_instead_of_starting_a_second_copy(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, slow("lamp"))
    rosaos_up_is_starting(data_dir, "lamp")
    row = listed(capsys, config, start_timeout=0.5)["lamp"]
    assert row["health"].startswith("starting: rosaos up is still starting lamp after 0.5 s")
    assert (row["via"], row["url"]) == ("served", None)
    assert installed_driver().STARTED == []


def test_list_without_checks_shows_that_rosaos_up_is_starting_it(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, slow("lamp"))
    rosaos_up_is_starting(data_dir, "lamp")
    assert listed(capsys, config, check=False)["lamp"]["health"] == "starting (not checked)"


def test_check_reports_why_rosaos_up_cannot_start_it(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, slow("lamp"))
    rosaos_up_is_starting(data_dir, "lamp", status="failed", error="the lamp has no power")
    assert check_device("lamp", config) == 1
    assert "lamp: check failed: rosaos up cannot start lamp: the lamp has no power" in capsys.readouterr().err
    assert installed_driver().STARTED == []


async def test_check_answers_once_rosaos_up_has_started_it(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, slow("lamp"))
    instance = build_world(load_config(config), load_drivers()).get("lamp")
    rosaos_up_is_starting(data_dir, "lamp")
    token = load_or_create_token(data_dir)
    async with open_device(instance, data_dir) as device, serve_http(device.server, token) as served:

        async def rosaos_up_finishes_starting() -> None:
            await asyncio.sleep(0.5)
            entry = RunFileEntry(url=served.url, pid=os.getpid(), status="healthy", since=now())
            runtime = RunFile(supervisor_pid=os.getpid(), devices={"lamp": entry})
            write_atomic(run_file_path(data_dir), runtime.model_dump_json())

        finishing = asyncio.create_task(rosaos_up_finishes_starting())
        code = await asyncio.to_thread(check_device, "lamp", config, True, 5.0, 30.0)
        await finishing
    assert code == 0, capsys.readouterr().err
    report = json.loads(capsys.readouterr().out)
    assert (report["via"], report["url"], report["state"]) == ("served", served.url, {"started_in": 0.0})
    assert installed_driver().STARTED == ["lamp"]  # only the copy "rosaos up" serves


@pytest.mark.slow  # starts device hosts (or the CLI on a terminal) as OS processes
async def test_list_while_rosaos_up_starts_waits_for_its_hosts_instead_of_starting_copies(
    tmp_path: Path,
    data_dir: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    slowsim: Path,
) -> None:
    monkeypatch.setenv("PYTHONPATH", str(slowsim))  # for the device host subprocess
    config = write_config(tmp_path / "rosaos.toml", data_dir, slow("lamp", start_seconds=1))
    world = build_world(load_config(config), load_drivers())
    supervisor = DeviceSupervisor(world, data_dir, load_or_create_token(data_dir), stop_grace=2)
    starting = asyncio.create_task(supervisor.start())
    try:
        await eventually(lambda: "lamp" in devices_not_ready(data_dir))
        assert await asyncio.to_thread(list_devices, config, True) == 0
        await starting
        [row] = json.loads(capsys.readouterr().out)
        assert (row["health"], row["via"]) == ("healthy", "served")
        assert row["url"] == supervisor.directory()["lamp"].url
    finally:
        await supervisor.stop()
    assert installed_driver().STARTED == []  # the host started it, in its own process; nothing started here


# --- progress -------------------------------------------------------------------------------------


def test_progress_says_what_is_done_and_what_each_check_waits_for() -> None:
    progress = CheckProgress(["reachy", "lamp", "dog"])
    progress.update("lamp", "done")
    progress.update("reachy", "starting")
    progress.update("dog", "queued")
    out = StringIO()
    Console(file=out, width=200).print(progress)
    assert out.getvalue().startswith("Checking 3 devices: 1 done · reachy starting (0 s) · dog queued (0 s)")


def test_no_progress_is_written_when_stdout_is_not_a_terminal(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, slow("lamp", start_seconds=0.5))
    assert list_devices(config) == 0
    assert capsys.readouterr().err == ""


def run_on_a_terminal(*args: str, env: dict[str, str], within: float = 60) -> str:
    """Run the CLI with stdout and stderr on a pseudo-terminal; everything it wrote."""
    controller, terminal = pty.openpty()
    process = subprocess.Popen(
        [str(ROSAOS), *args], stdin=subprocess.DEVNULL, stdout=terminal, stderr=terminal, env=env
    )
    os.close(terminal)
    output = b""
    deadline = time.monotonic() + within
    try:
        while time.monotonic() < deadline:
            try:
                chunk = os.read(controller, 65536)
            except OSError:  # EIO: the process closed the terminal
                break
            if not chunk:
                break
            output += chunk
    finally:
        os.close(controller)
        process.kill()
        process.wait()
    return output.decode(errors="replace")


@pytest.mark.slow  # starts device hosts (or the CLI on a terminal) as OS processes
def test_on_a_terminal_the_list_shows_progress_while_devices_start(
    tmp_path: Path, data_dir: Path, slowsim: Path
) -> None:
    body = slow("lamp", start_seconds=1.5) + slow("fan")
    config = write_config(tmp_path / "rosaos.toml", data_dir, body)
    env = os.environ | {"PYTHONPATH": str(slowsim), "COLUMNS": "200"}
    output = run_on_a_terminal("devices", "list", "--config", str(config), env=env)
    assert "Checking 2 devices: 0 done · lamp starting" in output
    assert "fan queued" in output  # one slowsim instance starts at a time
    assert output.count("healthy (not served)") == 2


def test_serve_device_refuses_an_instance_that_rosaos_up_is_starting(
    tmp_path: Path, data_dir: Path, capsys: pytest.CaptureFixture[str], slowsim: Path
) -> None:
    config = write_config(tmp_path / "rosaos.toml", data_dir, slow("lamp"))
    rosaos_up_is_starting(data_dir, "lamp")
    assert serve_device_command("lamp", config) == 1
    assert "lamp belongs to the running `rosaos up` (starting)" in capsys.readouterr().err
    assert installed_driver().STARTED == []
