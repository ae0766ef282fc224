"""How many worker processes may live at once, by default: sized to the machine.

A burst of commands (a hundred lamps switched in one second) must not fork a hundred workers on
two cores: they would fight for the CPU and the memory, and every command would be slow. Jobs
beyond the cap wait in the pool's queue, in order, and start as workers free up
(:class:`~rosaos.processes.pool.WorkerPool`). The default allows a few workers per core, and
never more than the available memory can hold at ``WORKER_MIB`` each.
"""

from __future__ import annotations

import os
from pathlib import Path

PER_CORE = 6
"""Workers per core: a worker mostly waits on a device or a model, so a core carries several."""
WORKER_MIB = 64
"""Memory budgeted per worker: a forked worker's own pages plus its share of the fork server's."""
LEAST = 4


def default_max_workers() -> int:
    """``PER_CORE`` per core, at most what the available memory holds, and at least ``LEAST``."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    by_cpu = PER_CORE * max(1, cores)
    available = _available_mib()
    by_memory = available // WORKER_MIB if available is not None else by_cpu
    return max(LEAST, min(by_cpu, by_memory))


def _available_mib() -> int | None:
    """``MemAvailable`` from /proc/meminfo (Linux); None elsewhere."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) // 1024
    except (OSError, ValueError, IndexError):
        return None
    return None
