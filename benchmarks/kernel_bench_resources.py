"""Memory and start-up for ``kernel.py``, and the machine the figures were taken on.

Memory is read from ``/proc/<pid>/status`` (``VmRSS`` and ``RssAnon``) of whichever process the
measurement names: a warm worker, the fork server, the device host or this process. Start-up is
``python -m rosaos.processes.worker`` from spawn to its ``ready`` line; each kernel's own
start-up is timed by :func:`kernel_bench_harness.running_kernel`.
"""

from __future__ import annotations

import contextlib
import datetime
import os
import platform
from pathlib import Path
from typing import Any

from kernel_bench_harness import now

# --- machine and processes ---------------------------------------------------------------------------


def machine() -> dict[str, Any]:
    """What the figures were taken on: date, cores, CPU, Python, platform, load average."""
    cpu = ""
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    return {
        "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
        "cores": os.cpu_count(),
        "usable_cores": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "cpu": cpu,
        "python": platform.python_version(),
        "implementation": platform.python_implementation(),
        "platform": platform.platform(),
        "load_average_start": list(os.getloadavg()),
    }


def memory(pid: int) -> dict[str, int | None]:
    """VmRSS and RssAnon (private heap, the cost of one more such process) of ``pid``, in bytes."""
    fields: dict[str, int | None] = {"rss": None, "rss_anon": None}
    with contextlib.suppress(OSError, ValueError, IndexError):
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                fields["rss"] = int(line.split()[1]) * 1024
            elif line.startswith("RssAnon:"):
                fields["rss_anon"] = int(line.split()[1]) * 1024
    return fields


# --- start-up -------------------------------------------------------------------------------------------


async def worker_start(times: int) -> list[float]:
    """Seconds from spawning ``python -m rosaos.processes.worker`` to its ``ready`` line."""
    from rosaos.processes.pool import WorkerPool

    seconds = []
    for _ in range(times):
        pool = WorkerPool(size=1)
        started = now()
        try:
            await pool.start()
            seconds.append(now() - started)
        finally:
            await pool.stop()
    return seconds
