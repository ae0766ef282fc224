"""Footprint of `rosaos up` on the demo world: time to "rosaOS is up", and memory (PSS) per process.

Starts the real command, as a user would, in a fresh data directory on a free port, waits for the
banner, lets it idle for a moment, then reads every process of its tree from /proc: PSS (the
shared pages split among the processes that map them, so the sum is the tree's real cost), USS
(its private pages, which other processes on the machine cannot deflate), RSS,
and a role from its command line (kernel, worker, fork server, device host of which instance, the
Reachy daemon). Linux only (/proc/PID/smaps_rollup). It measures, it does not assert.

    .venv/bin/python benchmarks/footprint.py [--runs 3] [--idle 5] [--json benchmarks/results/footprint.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

BANNER = "rosaOS is up at"
START_LIMIT = 300.0
"""Seconds to wait for the banner before the run counts as failed."""


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def children(pid: int) -> list[int]:
    """Every descendant of ``pid``, from /proc (no psutil needed)."""
    parents: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parents.setdefault(int(fields[1]), []).append(int(entry.name))
    found, todo = [], [pid]
    while todo:
        for child in parents.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def memory_kib(pid: int) -> dict[str, int]:
    """PSS, RSS and USS in KiB from /proc/PID/smaps_rollup.

    USS (the private pages, clean and dirty) is what the process alone costs: unlike PSS it does
    not shrink when other processes on the machine (another venv's, hard-linked by uv) map the
    same library files, so it is the figure to compare on a shared machine.
    """
    values: dict[str, int] = {"uss": 0}
    for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
        match = re.match(r"(Pss|Rss|Private_Clean|Private_Dirty):\s+(\d+) kB", line)
        if match and match.group(1).startswith("Private"):
            values["uss"] += int(match.group(2))
        elif match:
            values[match.group(1).lower()] = int(match.group(2))
    return values


def host_instances(data_dir: Path) -> dict[int, str]:
    """Device host pid → its instances' names, from the supervisor's ``run/devices.json``."""
    names: dict[int, list[str]] = {}
    for name, row in served(data_dir).items():
        if row.get("pid"):
            names.setdefault(row["pid"], []).append(name)
    return {pid: ", ".join(sorted(instances)) for pid, instances in names.items()}


def served(data_dir: Path) -> dict[str, Any]:
    """The supervisor's ``run/devices.json``: instance → pid, status, url."""
    try:
        devices = json.loads((data_dir / "run" / "devices.json").read_text()).get("devices", {})
    except (OSError, ValueError):
        return {}
    return devices if isinstance(devices, dict) else {}


def cpu_seconds(pids: list[int]) -> float:
    """User + system CPU time the processes have used so far (reaped children included).

    Unlike wall time, this barely depends on what else the machine runs: on a busy machine it
    says what start-up costs, where the wall time mostly says how long the queue for a core was.
    """
    ticks = os.sysconf("SC_CLK_TCK")
    total = 0
    for pid in pids:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += sum(int(value) for value in fields[11:15])  # utime, stime, cutime, cstime
    return total / ticks


SLOW_BOOT = "reachy"
"""The demo world's instance that boots in the background (MuJoCo), reported apart."""


def wait_all_healthy(data_dir: Path, started: float) -> dict[str, float]:
    """Seconds from the start until each served instance was first seen healthy (the Reachy sim
    boots on); an instance never seen healthy within START_LIMIT is missing."""
    first: dict[str, float] = {}
    while time.perf_counter() - started < START_LIMIT:
        devices = served(data_dir)
        for name, row in devices.items():
            if row.get("status") == "healthy" and name not in first:
                first[name] = round(time.perf_counter() - started, 2)
        if devices and len(first) == len(devices):
            break
        time.sleep(0.1)
    return first


def command_line(pid: int) -> str:
    return " ".join(Path(f"/proc/{pid}/cmdline").read_bytes().decode(errors="replace").split("\0"))


def parent(pid: int) -> int:
    return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])


def is_fork_server(pid: int, kernel: int, hosts: dict[int, str]) -> bool:
    """Started as ``python -m rosaos.processes.forkserver``, or forked from the kernel (the zygote
    of ``rosaos.processes.zygote``: the kernel's child with the kernel's command line)."""
    if pid == kernel or pid in hosts:  # a forked device host has the kernel's command line too
        return False
    line = command_line(pid)
    return "rosaos.processes.forkserver" in line or (parent(pid) == kernel and line == command_line(kernel))


def role(pid: int, hosts: dict[int, str], kernel: int) -> str:
    """What a process of the tree is, read from its command line and its parent."""
    line = command_line(pid)
    if pid == kernel:
        return "kernel (rosaos up)"
    if "rosaos.processes.worker" in line:
        return "worker"
    if pid in hosts:  # a host forked from the kernel (rosaos.devices.host_zygote) has its command line
        return f"device host {hosts[pid]}"
    # Workers are forked from the fork server and keep its command line: tell them by parent.
    if is_fork_server(parent(pid), kernel, hosts):
        return "worker (forked)"
    if is_fork_server(pid, kernel, hosts):
        return "fork server"
    if "rosaos.devices.host" in line:
        return f"device host {hosts.get(pid, '?')}"
    if "reachy" in line.lower() and "daemon" in line.lower():
        return "reachy daemon"
    return Path(line.split(" ")[0]).name or "other"


def one_run(idle: float) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as home:
        env = dict(os.environ, ROSAOS_DATA_DIR=str(Path(home) / "data"), COLUMNS="200")
        env.pop("ROSAOS_CONFIG", None)
        command = [sys.executable, "-m", "rosaos.cli", "up", "--port", str(free_port())]
        started = time.perf_counter()
        up = subprocess.Popen(
            command, cwd=home, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
        )
        assert up.stdout is not None
        lines: list[str] = []
        try:
            for line in up.stdout:
                lines.append(line.rstrip())
                if BANNER in line:
                    break
                if time.perf_counter() - started > START_LIMIT:
                    raise RuntimeError(f"no banner after {START_LIMIT:.0f} s")
            else:
                raise RuntimeError("rosaos up exited before its banner:\n" + "\n".join(lines[-20:]))
            start_seconds = time.perf_counter() - started
            start_cpu = cpu_seconds([up.pid, *children(up.pid)])
            statuses = {name: row.get("status") for name, row in served(Path(home) / "data").items()}
            healthy = wait_all_healthy(Path(home) / "data", started)
            expected = served(Path(home) / "data")
            all_healthy = max(healthy.values()) if healthy and len(healthy) == len(expected) else None
            fast = [seconds for name, seconds in healthy.items() if name != SLOW_BOOT]
            fast_healthy = max(fast) if fast and len(fast) == len(set(expected) - {SLOW_BOOT}) else None
            time.sleep(idle)
            processes = []
            hosts = host_instances(Path(home) / "data")
            for pid in [up.pid, *children(up.pid)]:
                try:
                    processes.append({"pid": pid, "role": role(pid, hosts, up.pid), **memory_kib(pid)})
                except OSError:  # ended between the listing and the read
                    continue
        finally:
            up.send_signal(signal.SIGINT)
            try:
                up.wait(30)
            except subprocess.TimeoutExpired:
                up.kill()
                up.wait()
    total = sum(p.get("pss", 0) for p in processes)
    daemon = sum(p.get("pss", 0) for p in processes if p["role"] == "reachy daemon")
    return {
        "start_seconds": round(start_seconds, 2),
        "start_cpu_seconds": round(start_cpu, 2),
        "statuses_at_banner": statuses,
        "all_devices_healthy_seconds": all_healthy,
        "all_but_reachy_healthy_seconds": fast_healthy,
        "healthy_seconds": healthy,
        "processes": processes,
        "pss_total_mib": round(total / 1024, 1),
        "pss_without_reachy_daemon_mib": round((total - daemon) / 1024, 1),
        "uss_total_mib": round(sum(p.get("uss", 0) for p in processes) / 1024, 1),
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--runs", type=int, default=3, help="starts of rosaos up (default 3)")
    parser.add_argument(
        "--idle", type=float, default=5.0, help="seconds after the banner before reading memory"
    )
    parser.add_argument("--json", type=Path, default=Path("benchmarks/results/footprint.json"))
    args = parser.parse_args()
    console = Console()
    runs = []
    for number in range(1, args.runs + 1):
        console.print(f"run {number}/{args.runs}: starting rosaos up (demo world)…")
        runs.append(one_run(args.idle))
    starts = [run["start_seconds"] for run in runs]
    summary = Table(title="rosaos up, demo world")
    for column in ("figure", "min", "median", "max"):
        summary.add_column(column, justify="right" if column != "figure" else "left")
    for label, values in (
        ("start to banner (s)", starts),
        ("CPU time of the tree until the banner (s)", [run["start_cpu_seconds"] for run in runs]),
        ("start to every device healthy (s)", [run["all_devices_healthy_seconds"] or -1 for run in runs]),
        ("the same, all but the Reachy (s)", [run["all_but_reachy_healthy_seconds"] or -1 for run in runs]),
        ("PSS, whole tree (MiB)", [run["pss_total_mib"] for run in runs]),
        ("PSS without Reachy daemon (MiB)", [run["pss_without_reachy_daemon_mib"] for run in runs]),
        ("USS, whole tree (MiB)", [run["uss_total_mib"] for run in runs]),
        ("processes", [len(run["processes"]) for run in runs]),
    ):
        summary.add_row(label, f"{min(values):g}", f"{statistics.median(values):g}", f"{max(values):g}")
    console.print(summary)
    last = Table(title="PSS by process (last run)")
    last.add_column("role")
    last.add_column("PSS MiB", justify="right")
    last.add_column("USS MiB", justify="right")
    last.add_column("RSS MiB", justify="right")
    for process in sorted(runs[-1]["processes"], key=lambda p: -p.get("pss", 0)):
        last.add_row(
            process["role"],
            *(f"{process.get(key, 0) / 1024:.1f}" for key in ("pss", "uss", "rss")),
        )
    console.print(last)
    console.print(f"statuses at the banner (last run): {runs[-1]['statuses_at_banner']}")
    report = {
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(), "load": os.getloadavg()},
        "runs": runs,
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=2))
    console.print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
