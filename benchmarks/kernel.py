"""Kernel benchmarks on the Tapo simulator: chat-to-device latency, event throughput, memory.

Every figure comes from a real :class:`~rosaos.kernel.runtime.Kernel` started in this process on
loopback (its own temporary data directory), with its device host and worker subprocesses, and
scripted ``FunctionModel``s (``benchmarks/bench_models.py``) instead of an LLM:

1. **Latency** from ``POST /chat`` to the bulb's state changing, with a kernel model that plans at
   once and a worker model that calls the tool at once; p50/p95/min/max over ``--runs`` runs that
   alternate ``turn_on`` and ``turn_off``, for a warm pool (``pool_size = 2``) and for no pool
   (``pool_size = 0``: every process spawns a one-off worker). A poller thread reads ``get_state``
   over one kept-open MCP session, in a tight loop from the moment the worker model asks for the
   tool (the state cannot change earlier, and polling sooner would take CPU from the worker
   start-up being measured). Both models stamp the path (``CLOCK_MONOTONIC``, shared by all
   processes), so the total is broken down by stage.
2. **Throughput** of the event queue and the kernel loop with a no-op kernel model: a separate
   load-generator process posts ``--events`` chats from ``--clients`` concurrent httpx clients;
   the store's own commit and handled time stamps give the enqueue and end-to-end rates.
3. **Memory** (RSS, and its anonymous part) of a warm worker, a device host and the kernel.

Also timed: kernel start-up, worker spawn-to-ready, and single HTTP/MCP round trips.

Prints tables and writes JSON (``benchmarks/results/kernel.json`` unless ``--json PATH``)::

    .venv/bin/python benchmarks/kernel.py            # full run, about 2 minutes on 2 cores
    .venv/bin/python benchmarks/kernel.py --quick    # fewer iterations, about 1 minute

Two experiments try out changes to rosaOS without editing it: ``--tcp-nodelay`` forces
``TCP_NODELAY`` on every socket of the kernel, the device hosts and the workers (what Nagle's
algorithm costs the HTTP surfaces); ``--kernel-session`` keeps the kernel agent's in-process MCP
toolset open across events instead of opening a session for every event.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import datetime
import functools
import json
import os
import platform
import re
import statistics
import sys
import tempfile
import threading
import time
from collections.abc import AsyncIterator, Awaitable, Callable, Iterator
from concurrent.futures import Future
from pathlib import Path
from typing import TYPE_CHECKING, Any

import httpx

if TYPE_CHECKING:
    from rosaos.kernel.runtime import Kernel

HERE = Path(__file__).resolve().parent
DEFAULT_JSON = HERE / "results" / "kernel.json"
DEVICE = "kitchen_light"
WORLD = f"""
[devices.{DEVICE}]
driver = "tapo"
description = "Ceiling light in the kitchen"
sim = {{ on = false }}
"""
SECTIONS = ("warm", "cold", "throughput", "worker-start")
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


# --- machine and processes ---------------------------------------------------------------------------


def machine() -> dict[str, Any]:
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
    """The pid of the device's host process, from the supervisor's runtime file."""
    from rosaos.devices.runtime import read_runtime_file

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


# --- the state poller --------------------------------------------------------------------------------


class StatePoller:
    """Reads the device's ``get_state`` in a tight loop, on its own thread and event loop.

    One MCP session stays open. Its own thread keeps it off the kernel's event loop (the GIL is
    still shared, but each poll mostly waits on the socket). ``async with`` it.
    """

    def __init__(self, url: str, token: str) -> None:
        self.url = url
        self.token = token
        self._loop: asyncio.AbstractEventLoop | None = None
        self._ready: Future[None] = Future()
        self._stop: asyncio.Event | None = None
        self._thread = threading.Thread(target=self._run, name="state-poller", daemon=True)

    async def __aenter__(self) -> StatePoller:
        self._thread.start()
        async with asyncio.timeout(30):
            await asyncio.wrap_future(self._ready)
        return self

    async def __aexit__(self, *exc: object) -> None:
        if self._loop is not None and self._stop is not None:
            self._loop.call_soon_threadsafe(self._stop.set)
        await asyncio.to_thread(self._thread.join, 10)

    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except BaseException as error:
            if not self._ready.done():
                self._ready.set_exception(error)

    async def _main(self) -> None:
        from rosaos.devices.client import DeviceClient

        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        async with DeviceClient(self.url, self.token, 10, DEVICE) as client:
            self._client = client
            await client.get_state()
            self._ready.set_result(None)
            await self._stop.wait()

    def read(self) -> Future[dict[str, Any]]:
        """One ``get_state``."""
        assert self._loop is not None
        return asyncio.run_coroutine_threadsafe(self._client.get_state(), self._loop)

    def watch(
        self, key: str, value: Any, timeout: float, gate: Callable[[], bool] | None = None
    ) -> tuple[Future[None], Future[dict[str, Any]]]:
        """Poll until ``state[key] == value``: (first poll done, result). The result says when it was seen.

        After the first poll, wait (checking every 2 ms) until ``gate()`` is true before polling
        again, so a tight loop does not steal CPU from the work it is waiting for.
        """
        assert self._loop is not None
        first: Future[None] = Future()
        result = asyncio.run_coroutine_threadsafe(self._watch(key, value, timeout, first, gate), self._loop)
        return first, result

    async def _watch(
        self, key: str, value: Any, timeout: float, first: Future[None], gate: Callable[[], bool] | None
    ) -> dict[str, Any]:
        periods: list[float] = []
        deadline = now() + timeout
        try:
            while now() < deadline:
                sent = now()
                state = await self._client.get_state()
                seen = now()
                periods.append(seen - sent)
                if state.get(key) == value:
                    if not first.done():
                        first.set_result(None)
                    return {"sent": sent, "seen": seen, "polls": len(periods), "periods": periods}
                if not first.done():
                    first.set_result(None)
                    while gate is not None and now() < deadline:
                        if gate():
                            break
                        await asyncio.sleep(0.002)
            raise TimeoutError(f"{DEVICE} did not reach {key}={value!r} within {timeout:g} s")
        except BaseException as error:
            if not first.done():
                first.set_exception(error)
            raise


class WorkerTrace:
    """The worker model's stamps, read as the trace file grows (by the poller's thread only)."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._offset = 0
        self._partial = b""
        self._seen: set[tuple[int, str]] = set()

    def has(self, run: int, phase: str) -> bool:
        if (run, phase) not in self._seen:
            try:
                with self.path.open("rb") as handle:
                    handle.seek(self._offset)
                    data = handle.read()
            except FileNotFoundError:
                return False
            self._offset += len(data)
            *lines, self._partial = (self._partial + data).split(b"\n")
            for line in lines:
                entry = json.loads(line)
                self._seen.add((entry["run"], entry["phase"]))
        return (run, phase) in self._seen


# --- 1. latency ----------------------------------------------------------------------------------------

STAGES = (
    ("post_to_committed", "POST → event committed"),
    ("committed_to_kernel_model", "committed → kernel model called"),
    ("kernel_model_to_launched", "kernel model → launch_process returned"),
    ("launched_to_worker_model", "launched → worker model called"),
    ("worker_model_to_tool_returned", "worker model → tool result back"),
)
TOTALS = (
    ("post_to_state_seen", "POST → state seen by poller"),
    ("post_to_accepted", "POST → 202 received"),
    ("post_to_tool_returned", "POST → tool result at worker"),
    ("post_to_callback", "POST → callback read by kernel"),
    ("poll_period", "poll period (one get_state)"),
)


def read_worker_trace(path: Path) -> dict[int, dict[str, Any]]:
    stamps: dict[int, dict[str, Any]] = {}
    if path.exists():
        for line in path.read_text(encoding="utf-8").splitlines():
            entry = json.loads(line)
            stamps.setdefault(entry["run"], {})[entry["phase"]] = entry["t"]
            stamps[entry["run"]]["pid"] = entry["pid"]
    return stamps


async def latency(
    label: str, pool_size: int, runs: int, warmup: int, first_run: int, work: Path
) -> dict[str, Any]:
    """``runs`` chat-to-device runs (after ``warmup`` unrecorded ones) on a kernel with ``pool_size``."""
    import bench_models

    trace = Trace()
    trace_file = work / f"trace-{label}.jsonl"
    async with running_kernel(
        pool_size=pool_size, kernel_model=bench_models.kernel_model(), trace=trace, trace_file=trace_file
    ) as (kernel, start_seconds):
        endpoint = kernel.endpoints()[DEVICE]
        assert endpoint.url is not None
        memory_fresh = {w.pid: memory(w.pid) for w in kernel.manager.pool.stats()}
        headers = {"Authorization": f"Bearer {kernel.token}"}
        samples: list[dict[str, Any]] = []
        async with (
            httpx.AsyncClient(base_url=kernel.url, headers=headers, timeout=30) as api,
            StatePoller(endpoint.url, endpoint.token) as poller,
        ):
            state = await poller_state(poller)
            worker_trace = WorkerTrace(trace_file)
            for index in range(warmup + runs):
                run = first_run + index
                tool, expected = ("turn_off", False) if state else ("turn_on", True)
                gate = functools.partial(worker_trace.has, run, "worker_model")
                first, result = poller.watch("on", expected, SETTLE_TIMEOUT, gate)
                await asyncio.wrap_future(first)
                posted = now()
                response = await api.post("/chat", json={"text": f"bench {run} {DEVICE} {tool}"})
                accepted = now()
                response.raise_for_status()
                seen = await asyncio.wrap_future(result)
                await settle(kernel)
                state = expected
                if index >= warmup:
                    rss = {w.pid: w.rss_bytes for w in kernel.manager.pool.stats()}
                    sample = {"run": run, "tool": tool, "posted": posted, "accepted": accepted}
                    samples.append({**sample, "poll": seen, "rss": rss})
                await asyncio.sleep(0.02)
        worker_stats = kernel.manager.pool.stats()
        memory_after = {w.pid: memory(w.pid) for w in worker_stats}
        host_pid = device_host_pid(kernel)
        memory_host = memory(host_pid) if host_pid else {}
        fork_server = kernel.manager.pool.fork_server
        memory_fork_server = memory(fork_server.pid) if fork_server and fork_server.pid else {}
        memory_kernel = memory(os.getpid())
    return {
        "label": label,
        "pool_size": pool_size,
        "kernel_start_seconds": start_seconds,
        "warm_worker_pids": sorted(memory_fresh),
        **_latency_figures(samples, trace, read_worker_trace(trace_file)),
        "memory": {
            "workers_fresh": list(memory_fresh.values()),
            "workers_after_runs": list(memory_after.values()),
            "device_host": memory_host,
            "fork_server": memory_fork_server,
            "kernel_process": memory_kernel,
        },
    }


async def poller_state(poller: StatePoller) -> bool:
    """The bulb's current ``on``, read through the poller."""
    return bool((await asyncio.wrap_future(poller.read()))["on"])


def _latency_figures(
    samples: list[dict[str, Any]], trace: Trace, worker: dict[int, dict[str, Any]]
) -> dict[str, Any]:
    import bench_models

    series: dict[str, list[float]] = {key: [] for key, _ in (*STAGES, *TOTALS)}
    runs = []
    for sample in samples:
        run, posted = sample["run"], sample["posted"]
        launched, process_id = trace.launched[run]
        stamps = {
            "posted": posted,
            "committed": trace.committed[run],
            "kernel_model": bench_models.KERNEL_TRACE[run]["kernel_model"],
            "launched": launched,
            "worker_model": worker[run]["worker_model"],
            "tool_returned": worker[run]["tool_returned"],
            "callback": bench_models.CALLBACKS[process_id],
        }
        figures = {
            "post_to_committed": stamps["committed"] - posted,
            "committed_to_kernel_model": stamps["kernel_model"] - stamps["committed"],
            "kernel_model_to_launched": stamps["launched"] - stamps["kernel_model"],
            "launched_to_worker_model": stamps["worker_model"] - stamps["launched"],
            "worker_model_to_tool_returned": stamps["tool_returned"] - stamps["worker_model"],
            "post_to_state_seen": sample["poll"]["seen"] - posted,
            "post_to_accepted": sample["accepted"] - posted,
            "post_to_tool_returned": stamps["tool_returned"] - posted,
            "post_to_callback": stamps["callback"] - posted,
        }
        for key, value in figures.items():
            series[key].append(value * 1000)
        series["poll_period"].extend(p * 1000 for p in sample["poll"]["periods"])
        runs.append(
            {
                "run": run,
                "tool": sample["tool"],
                "process_id": process_id,
                "worker_pid": worker[run]["pid"],
                "worker_rss_after": sample["rss"].get(worker[run]["pid"]),
                "polls": sample["poll"]["polls"],
                "post_to_poll_sent": round((sample["poll"]["sent"] - posted) * 1000, 3),
                **{key: round(value * 1000, 3) for key, value in figures.items()},
            }
        )
    return {"ms": {key: summary(values) for key, values in series.items()}, "runs": runs}


# --- 2. throughput -------------------------------------------------------------------------------------


async def throughput(
    count: int, clients: int, round_trip_samples: int
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Post ``count`` chats from ``clients`` clients in another process; time enqueue and handling.

    Also returns the single-request round trips, timed on the same (idle) kernel first.
    """
    import bench_models

    async with running_kernel(pool_size=0, kernel_model=bench_models.noop_model()) as (kernel, start_seconds):
        single = {"kernel_start_seconds": start_seconds, **await round_trips(kernel, round_trip_samples)}
        handle_ms: list[float] = []
        handle = kernel.loop.handle

        async def timed_handle(event: Any) -> Any:
            started = now()
            try:
                return await handle(event)
            finally:
                handle_ms.append((now() - started) * 1000)

        kernel.loop.handle = timed_handle  # type: ignore[method-assign]
        # Warm up the API, the store and the agent, then start from an empty queue.
        headers = {"Authorization": f"Bearer {kernel.token}"}
        async with httpx.AsyncClient(base_url=kernel.url, headers=headers, timeout=30) as api:
            for index in range(20):
                (await api.post("/chat", json={"text": f"warm-up {index}"})).raise_for_status()
        await drained(kernel)
        handle_ms.clear()
        process = await asyncio.create_subprocess_exec(
            sys.executable,
            __file__,
            "--load-generator",
            kernel.url,
            str(count),
            str(clients),
            stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE,
        )
        out, _ = await process.communicate(kernel.token.encode())
        if process.returncode != 0:
            raise RuntimeError(f"the load generator failed (exit code {process.returncode})")
        load = json.loads(out)
        await drained(kernel)
        first, last = load["ids"]
        rows = await kernel.events.database.fetch(
            "SELECT count(*), min(time), max(time), min(handled_at), max(handled_at), "
            "sum(handled_at > ?) FROM events WHERE id BETWEEN ? AND ?",
            (load["last_ack"], first, last),
        )
        memory_kernel = memory(os.getpid())
    stored, first_commit, last_commit, first_handled, last_handled, after_enqueue = rows[0]
    tail = last_handled - load["last_ack"]
    return single, {
        "events": count,
        "clients": clients,
        "stored": stored,
        "errors": load["errors"],
        "enqueue_seconds": load["last_ack"] - load["first_send"],
        "enqueue_per_second": count / (load["last_ack"] - load["first_send"]),
        "commit_per_second": (stored - 1) / (last_commit - first_commit)
        if last_commit > first_commit
        else None,
        "end_to_end_seconds": last_handled - load["first_send"],
        "end_to_end_per_second": count / (last_handled - load["first_send"]),
        "handled_per_second": (stored - 1) / (last_handled - first_handled),
        "handled_after_enqueue": after_enqueue,
        "drain_per_second": after_enqueue / tail if after_enqueue >= 20 and tail > 0 else None,
        "backlog_at_last_ack": after_enqueue,
        "post_ms": summary(load["latencies_ms"]),
        "kernel_handle_ms": summary(handle_ms),
        "kernel_process_memory": memory_kernel,
    }


async def drained(kernel: Kernel, timeout: float = SETTLE_TIMEOUT) -> None:
    deadline = now() + timeout
    while await kernel.events.pending_count():
        if now() > deadline:
            raise TimeoutError(f"the queue did not drain within {timeout:g} s")
        await asyncio.sleep(0.02)


async def load_generator(url: str, count: int, clients: int, token: str) -> dict[str, Any]:
    """Post ``count`` chats as fast as ``clients`` sequential clients can; wall-clock times."""
    remaining = iter(range(count))
    latencies: list[float] = []
    ids: list[int] = []
    errors = 0
    headers = {"Authorization": f"Bearer {token}"}

    async def client() -> None:
        nonlocal errors
        async with httpx.AsyncClient(base_url=url, headers=headers, timeout=30) as http:
            await http.get("/health")  # connect before the clock starts
            await start.wait()
            for index in remaining:
                sent = time.perf_counter()
                response = await http.post("/chat", json={"text": f"noop {index}"})
                latencies.append((time.perf_counter() - sent) * 1000)
                if response.status_code == 202:
                    ids.append(response.json()["id"])
                else:
                    errors += 1

    start = asyncio.Event()
    tasks = [asyncio.create_task(client()) for _ in range(clients)]
    await asyncio.sleep(0.5)
    first_send = time.time()
    start.set()
    await asyncio.gather(*tasks)
    last_ack = time.time()
    return {
        "first_send": first_send,
        "last_ack": last_ack,
        "latencies_ms": latencies,
        "ids": [min(ids), max(ids)],
        "errors": errors,
    }


# --- 3. start-up and round trips -----------------------------------------------------------------------


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


async def round_trips(kernel: Kernel, times: int) -> dict[str, Any]:
    """Single requests: kernel ``GET /health``, MCP session open, ``get_state`` on an open session."""
    from rosaos.devices.client import DeviceClient

    endpoint = kernel.endpoints()[DEVICE]
    assert endpoint.url is not None
    health, opens, calls = [], [], []
    async with httpx.AsyncClient(base_url=kernel.url, timeout=30) as api:
        await api.get("/health")
        for _ in range(times):
            health.append(await timed(lambda: api.get("/health")))
    for _ in range(times):
        client = DeviceClient(endpoint.url, endpoint.token, 10, DEVICE)
        started = now()
        async with client:
            opens.append((now() - started) * 1000)
    async with DeviceClient(endpoint.url, endpoint.token, 10, DEVICE) as client:
        await client.get_state()
        for _ in range(times):
            calls.append(await timed(client.get_state))
    return {
        "kernel_health_ms": summary(health),
        "mcp_session_open_ms": summary(opens),
        "mcp_get_state_ms": summary(calls),
    }


async def timed(call: Callable[[], Awaitable[Any]]) -> float:
    started = now()
    await call()
    return (now() - started) * 1000


# --- report ----------------------------------------------------------------------------------------


def report(results: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console(width=None if sys.stdout.isatty() else 120)
    m, o = results["machine"], results["options"]
    console.print(
        f"[bold]rosaOS kernel benchmark[/bold]  {m['date']}  {m['cores']} cores ({m['cpu'] or 'cpu?'}), "
        f"Python {m['python']}, {m['platform']}\n"
        f"load average {fmt_load(m['load_average_start'])} at start, {fmt_load(m['load_average_end'])} "
        f"at end; experiments: tcp_nodelay={o['tcp_nodelay']}, kernel_session={o['kernel_session']}; "
        f"fork server {'off' if o['no_fork_server'] else 'on'}"
    )
    if results["latency"]:
        table = Table(title="Latency: POST /chat → Tapo sim state (ms)")
        for column in ("pool", "measure", "n", "p50", "p95", "min", "max"):
            table.add_column(column, justify="left" if column in ("pool", "measure") else "right")
        for mode in results["latency"]:
            pool = f"{mode['label']} (size {mode['pool_size']})"
            for key, name in (TOTALS[0], *[(k, f"  {n}") for k, n in STAGES], *TOTALS[1:]):
                row = mode["ms"][key]
                values = (ms(row.get(stat)) for stat in ("p50", "p95", "min", "max"))
                table.add_row(pool, name, str(row["n"]), *values)
                pool = ""
            table.add_section()
        console.print(table)

    if t := results.get("throughput"):
        table = Table(
            title=f"Throughput: {t['events']} events from {t['clients']} clients, no-op kernel model"
        )
        table.add_column("measure")
        table.add_column("value", justify="right")
        post, handle = t["post_ms"], t["kernel_handle_ms"]
        table.add_row("enqueue (POST /chat → 202), events/s", rate(t["enqueue_per_second"]))
        table.add_row("POST /chat latency under load, p50 / p95 ms", f"{ms(post['p50'])} / {ms(post['p95'])}")
        table.add_row("end to end (first POST → last handled), events/s", rate(t["end_to_end_per_second"]))
        table.add_row("kernel handling (first → last handled), events/s", rate(t["handled_per_second"]))
        table.add_row("kernel drain after the last 202, events/s", rate(t["drain_per_second"]))
        table.add_row("backlog at the last 202, events", str(t["backlog_at_last_ack"]))
        table.add_row(
            "kernel loop handle() per event, p50 / p95 ms", f"{ms(handle['p50'])} / {ms(handle['p95'])}"
        )
        console.print(table)

    table = Table(title="Memory and start-up")
    table.add_column("measure")
    table.add_column("value", justify="right")
    if warm := next((mode for mode in results["latency"] if mode["pool_size"]), None):
        memory_rows = [
            ("warm worker, fresh", warm["memory"]["workers_fresh"]),
            ("warm worker, after the runs", warm["memory"]["workers_after_runs"]),
            ("device host (Tapo sim)", [warm["memory"]["device_host"]]),
            ("kernel + benchmark process, after the warm-pool runs", [warm["memory"]["kernel_process"]]),
        ]
        for name, entries in memory_rows:
            table.add_row(f"{name}: RSS / anon MiB", mib_range(entries))
    for mode in results["latency"]:
        if mode["memory"].get("fork_server"):
            name = f"fork server ({mode['label']}), after the runs: RSS / anon MiB"
            table.add_row(name, mib_range([mode["memory"]["fork_server"]]))
    for mode in results["latency"]:
        table.add_row(
            f"kernel start, pool size {mode['pool_size']}, s", f"{mode['kernel_start_seconds']:.2f}"
        )
    if single := results.get("round_trips"):
        table.add_row(
            "kernel start, pool size 0 (throughput kernel), s", f"{single['kernel_start_seconds']:.2f}"
        )
        for key, name in (
            ("kernel_health_ms", "GET /health, one request"),
            ("mcp_session_open_ms", "MCP session open (initialize)"),
            ("mcp_get_state_ms", "MCP get_state on an open session"),
        ):
            row = single[key]
            table.add_row(f"{name}: p50 / min ms", f"{ms(row.get('p50'))} / {ms(row.get('min'))}")
    if starts := results.get("worker_spawn_to_ready_seconds"):
        table.add_row("worker spawn → ready (imports), median s", seconds_range(starts))
    console.print(table)
    console.print(f"JSON: {results['json']}")


def ms(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f}"


def rate(value: float | None) -> str:
    return "-" if value is None else f"{value:.0f}"


def fmt_load(values: list[float]) -> str:
    return " ".join(f"{v:.2f}" for v in values)


def mib_range(entries: list[dict[str, int | None]]) -> str:
    def one(key: str) -> str:
        values = [e[key] / 2**20 for e in entries if e.get(key)]
        if not values:
            return "-"
        low, high = min(values), max(values)
        return f"{low:.0f}" if round(low) == round(high) else f"{low:.0f}-{high:.0f}"

    return f"{one('rss')} / {one('rss_anon')}"


def seconds_range(values: list[float]) -> str:
    if not values:
        return "-"
    return f"{statistics.median(values):.2f} (min {min(values):.2f}, max {max(values):.2f})"


# --- main ------------------------------------------------------------------------------------------


def enable_tcp_nodelay(folder: Path) -> None:
    """The ``--tcp-nodelay`` experiment, for this process and (through PYTHONPATH) its children."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "sitecustomize.py").write_text(NODELAY_SITECUSTOMIZE, encoding="utf-8")
    os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(folder), os.environ.get("PYTHONPATH")) if p)
    exec(compile(NODELAY_SITECUSTOMIZE, "sitecustomize", "exec"), {})


async def run(options: argparse.Namespace) -> dict[str, Any]:
    results: dict[str, Any] = {"machine": machine(), "options": vars(options).copy(), "latency": []}
    results["options"]["json"] = str(options.json)
    sections = set(options.only or SECTIONS)
    with tempfile.TemporaryDirectory(prefix="rosaos-bench-work-") as tmp:
        work = Path(tmp)
        EXPERIMENTS.update(tcp_nodelay=options.tcp_nodelay, kernel_session=options.kernel_session)
        FORK_SERVER["on"] = not options.no_fork_server
        if options.tcp_nodelay:
            enable_tcp_nodelay(work / "nodelay")
        if "warm" in sections:
            with phase("latency, warm pool"):
                results["latency"].append(
                    await latency("warm pool", 2, options.runs, options.warmup, 1, work)
                )
        if "cold" in sections:
            label = "no pool" if FORK_SERVER["on"] else "no pool, no fork server"
            with phase(f"latency, {label}"):
                results["latency"].append(await latency(label, 0, options.cold_runs, 0, 100_000, work))
        if "throughput" in sections:
            with phase("round trips and throughput"):
                results["round_trips"], results["throughput"] = await throughput(
                    options.events, options.clients, options.round_trips
                )
        if "worker-start" in sections and options.worker_starts:
            with phase("worker start-up"):
                results["worker_spawn_to_ready_seconds"] = await worker_start(options.worker_starts)
    results["machine"]["load_average_end"] = list(os.getloadavg())
    return results


@contextlib.contextmanager
def phase(name: str) -> Iterator[None]:
    started = now()
    print(f"… {name}", file=sys.stderr, flush=True)
    yield
    print(f"  {name}: {now() - started:.1f} s", file=sys.stderr, flush=True)


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a short run (about a minute)")
    parser.add_argument("--only", nargs="+", choices=SECTIONS, help="run only these parts (default: all)")
    parser.add_argument("--runs", type=int, help="latency runs with the warm pool (default 40, quick 10)")
    parser.add_argument("--cold-runs", type=int, help="latency runs with no pool (default 6, quick 2)")
    parser.add_argument("--warmup", type=int, help="unrecorded warm-pool runs first (default 4, quick 2)")
    parser.add_argument("--events", type=int, help="events for the throughput test (default 1000, quick 300)")
    parser.add_argument(
        "--clients", type=int, default=8, help="concurrent clients posting events (default 8)"
    )
    parser.add_argument("--round-trips", type=int, help="single-request samples (default 30, quick 10)")
    parser.add_argument(
        "--worker-starts", type=int, help="worker spawn-to-ready samples (default 2, quick 0)"
    )
    parser.add_argument(
        "--json",
        "--out",
        type=Path,
        default=DEFAULT_JSON,
        help=f"where to write the JSON (default {DEFAULT_JSON})",
    )
    parser.add_argument(
        "--tcp-nodelay",
        action="store_true",
        help="experiment: force TCP_NODELAY on every socket (see the README)",
    )
    parser.add_argument(
        "--kernel-session",
        action="store_true",
        help="experiment: keep the kernel agent's MCP toolset open across events (see the README)",
    )
    parser.add_argument(
        "--no-fork-server",
        action="store_true",
        help="kernels with [kernel] fork_server = false: each one-off worker starts a new Python",
    )
    parser.add_argument(
        "--load-generator", nargs=3, metavar=("URL", "COUNT", "CLIENTS"), help=argparse.SUPPRESS
    )
    options = parser.parse_args(argv)
    defaults = {
        "runs": (40, 10),
        "warmup": (4, 2),
        "cold_runs": (6, 2),
        "events": (1000, 300),
        "round_trips": (30, 10),
        "worker_starts": (2, 0),
    }
    for name, (full, quick) in defaults.items():
        if getattr(options, name) is None:
            setattr(options, name, quick if options.quick else full)
    return options


def main(argv: list[str] | None = None) -> None:
    options = parse_args(argv)
    if options.load_generator:
        url, count, clients = options.load_generator
        token = sys.stdin.read().strip()
        print(json.dumps(asyncio.run(load_generator(url, int(count), int(clients), token))))
        return
    results = asyncio.run(run(options))
    results["json"] = str(options.json)
    options.json.parent.mkdir(parents=True, exist_ok=True)
    options.json.write_text(json.dumps(results, indent=2, default=str) + "\n", encoding="utf-8")
    report(results)


if __name__ == "__main__":
    main()
