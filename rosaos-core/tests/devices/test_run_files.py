"""The run files: what other commands learn about served instances, and stale files ignored."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from rosaos.devices.run_files import (
    RunFile,
    RunFileEntry,
    now,
    read_runtime_file,
    record_served_device,
    run_file_path,
    served_devices,
    write_atomic,
)


def dead_pid() -> int:
    """The pid of a process that has already exited."""
    process = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, check=True
    )
    return int(process.stdout)


def write_runtime(data_dir: Path, supervisor_pid: int, host_pid: int) -> None:
    entry = RunFileEntry(url="http://127.0.0.1:9/mcp", pid=host_pid, status="healthy", since=now())
    runtime = RunFile(supervisor_pid=supervisor_pid, devices={"kitchen_light": entry})
    write_atomic(run_file_path(data_dir), runtime.model_dump_json())


def test_a_live_supervisors_instances_are_served(data_dir: Path) -> None:
    write_runtime(data_dir, supervisor_pid=os.getpid(), host_pid=os.getpid())
    assert served_devices(data_dir)["kitchen_light"].url == "http://127.0.0.1:9/mcp"


def test_a_file_left_by_a_dead_supervisor_is_ignored(data_dir: Path) -> None:
    write_runtime(data_dir, supervisor_pid=dead_pid(), host_pid=os.getpid())
    assert read_runtime_file(data_dir) is None
    assert served_devices(data_dir) == {}


def test_an_instance_whose_host_died_is_not_served(data_dir: Path) -> None:
    write_runtime(data_dir, supervisor_pid=os.getpid(), host_pid=dead_pid())
    assert served_devices(data_dir) == {}


def test_serve_device_is_recorded_only_while_it_runs(data_dir: Path) -> None:
    with record_served_device(data_dir, "kitchen_light", "http://127.0.0.1:9100/mcp"):
        assert served_devices(data_dir)["kitchen_light"].pid == os.getpid()
    assert served_devices(data_dir) == {}


def test_runtime_files_are_owner_only(data_dir: Path) -> None:
    write_runtime(data_dir, supervisor_pid=os.getpid(), host_pid=os.getpid())
    assert run_file_path(data_dir).stat().st_mode & 0o077 == 0
