"""The kernel under test for ``kernel.py``: start, instrument, wait for it, always stop it.

A real :class:`~rosaos.kernel.runtime.Kernel` runs in this process on loopback, in a fresh
temporary data directory, with the Tapo sim served by a device host subprocess and workers that
import ``bench_models`` (this folder goes on their ``PYTHONPATH``). Also here: the clock every
stamp uses, the summary of a series of samples, and the ``--tcp-nodelay`` experiment, which
changes how the kernel and its children open sockets.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import re
import statistics
import tempfile
import time
from collections.abc import AsyncIterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rosaos.kernel.runtime import Kernel

HERE = Path(__file__).resolve().parent
DEVICE = "kitchen_light"
WORLD = f"""
[devices.{DEVICE}]
driver = "tapo"
description = "Ceiling light in the kitchen"
sim = {{ on = false }}
"""
FORK_SERVER = {"on": True}
"""``[kernel] fork_server`` for the kernels under test; ``--no-fork-server`` turns it off."""
EXPERIMENTS = {"tcp_nodelay": False, "kernel_session": False}
"""Set from ``--tcp-nodelay`` and ``--kernel-session``: changes to rosaOS tried out, not its defaults."""
SETTLE_TIMEOUT = 60.0
"""Seconds one latency run (or the wait for a drained queue) may take before the benchmark gives up."""

NODELAY_SITECUSTOMIZE = '''\
"""Benchmark experiment (benchmarks/kernel.py --tcp-nodelay): TCP_NODELAY on every TCP socket.

asyncio sets TCP_NODELAY only on sockets whose proto is IPPROTO_TCP; a socket made with
socket.socket(family, SOCK_STREAM) has proto 0, so its accepted connections keep Nagle on.
"""
import asyncio.base_events
import socket


def _set_nodelay(sock):
    if sock.family in {socket.AF_INET, socket.AF_INET6} and sock.type == socket.SOCK_STREAM:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


asyncio.base_events._set_nodelay = _set_nodelay
'''


def now() -> float:
    """``CLOCK_MONOTONIC``, the clock the models stamp with (see ``bench_models.now``)."""
    return time.clock_gettime(time.CLOCK_MONOTONIC)


def enable_tcp_nodelay(folder: Path) -> None:
    """The ``--tcp-nodelay`` experiment, for this process and (through PYTHONPATH) its children."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "sitecustomize.py").write_text(NODELAY_SITECUSTOMIZE, encoding="utf-8")
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(folder), os.environ.get("PYTHONPATH")) if p)
    exec(compile(NODELAY_SITECUSTOMIZE, "sitecustomize", "exec"), {})


# --- statistics --------------------------------------------------------------------------------------


def percentile(samples: list[float], fraction: float) -> float:
    ordered = sorted(samples)
    return ordered[min(len(ordered) - 1, round(fraction * (len(ordered) - 1)))]


def summary(samples: list[float]) -> dict[str, Any]:
    """n, p50, p95, min, max and mean of ``samples`` (empty: only n)."""
    if not samples:
        return {"n": 0}
    return {
        "n": len(samples),
        "p50": percentile(samples, 0.5),
        "p95": percentile(samples, 0.95),
        "min": min(samples),
        "max": max(samples),
        "mean": statistics.fmean(samples),
    }


# --- the kernel under test ---------------------------------------------------------------------------


class Trace:
    """Time stamps the kernel's own process records, by run number (the models add theirs)."""

    def __init__(self) -> None:
        self.committed: dict[int, float] = {}
        self.launched: dict[int, tuple[float, int]] = {}
        """run -> (when launch_process returned, process id)."""


_RUN = re.compile(r"bench (\d+)")


@contextlib.asynccontextmanager
async def running_kernel(
    *, pool_size: int, kernel_model: Any, trace: Trace | None = None, trace_file: Path | None = None
) -> AsyncIterator[tuple[Kernel, float]]:
    """A started kernel in a temporary data directory, with the Tapo sim; always stopped.

    Yields ``(kernel, start_seconds)``. With ``trace``, the event store's ``append`` and the
    process manager's ``launch`` are wrapped to stamp the runs.
    """
    from rosaos.config import load_config
    from rosaos.devices.world import build_world
    from rosaos.kernel.runtime import Kernel
    from rosaos.models.select import ModelSpec
    from rosaos.plugins import load_drivers

    with tempfile.TemporaryDirectory(prefix="rosaos-bench-") as tmp:
        home = Path(tmp)
        (home / "rosaos.toml").write_text(
            f'data_dir = "{home / "data"}"\n[kernel]\npool_size = {pool_size}\n'
            f"fork_server = {str(FORK_SERVER['on']).lower()}\n{WORLD}",
            encoding="utf-8",
        )
        config = load_config(home / "rosaos.toml")
        python_path = os.pathsep.join(p for p in (str(HERE), os.environ.get("PYTHONPATH")) if p)
        env = {"PYTHONPATH": python_path, "ROSAOS_WORKER_LOG": "WARNING"}
        if trace_file is not None:
            env["ROSAOS_BENCH_TRACE"] = str(trace_file)
        kernel = Kernel(
            config,
            build_world(config, load_drivers()),
            kernel_model=kernel_model,
            process_model=ModelSpec(model="python:bench_models:worker_model"),
            worker_env=env,
        )
        try:
            started = now()
            await kernel.start(host="127.0.0.1", port=0)
            await kernel.manager.pool.wait_until_warm()
            start_seconds = now() - started
            if trace is not None:
                _instrument(kernel, trace)
            async with contextlib.AsyncExitStack() as stack:
                if EXPERIMENTS["kernel_session"]:
                    # Open the kernel agent's toolsets once: each run then reuses the MCP session.
                    await stack.enter_async_context(kernel.loop.agent)
                yield kernel, start_seconds
        finally:
            await kernel.stop()


def _instrument(kernel: Kernel, trace: Trace) -> None:
    store = kernel.events
    append = store.append
    launch = kernel.manager.launch

    async def traced_append(event: Any) -> Any:
        appended = await append(event)
        if event.kind == "user_typed" and (match := _RUN.match(event.payload.text)):
            trace.committed[int(match.group(1))] = now()
        return appended

    async def traced_launch(task: str, devices: list[str]) -> Any:
        info = await launch(task, devices)
        if match := _RUN.match(task):
            trace.launched[int(match.group(1))] = (now(), info.id)
        return info

    store.append = traced_append  # type: ignore[method-assign]
    kernel.manager.launch = traced_launch  # type: ignore[method-assign]


def device_host_pid(kernel: Kernel) -> int | None:
    """The pid of the device's host process, from the supervisor's run file."""
    from rosaos.devices.run_files import read_runtime_file

    runtime = read_runtime_file(kernel.data_dir)
    entry = runtime.devices.get(DEVICE) if runtime else None
    return entry.pid if entry else None


async def settle(kernel: Kernel, timeout: float = SETTLE_TIMEOUT) -> None:
    """Wait until no process runs, no worker is busy or one-off, and no event is pending."""
    deadline = now() + timeout
    while now() < deadline:
        workers = kernel.manager.pool.stats()
        if (
            not kernel.manager.list()
            and not any(w.state == "busy" or w.one_off for w in workers)
            and await kernel.events.pending_count() == 0
        ):
            return
        await asyncio.sleep(0.01)
    raise TimeoutError(f"the kernel did not settle within {timeout:g} s")


async def drained(kernel: Kernel, timeout: float = SETTLE_TIMEOUT) -> None:
    """Wait until the event queue is empty."""
    deadline = now() + timeout
    while await kernel.events.pending_count():
        if now() > deadline:
            raise TimeoutError(f"the queue did not drain within {timeout:g} s")
        await asyncio.sleep(0.02)
