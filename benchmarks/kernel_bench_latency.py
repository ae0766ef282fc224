"""Latency for ``kernel.py``: ``POST /chat`` to the Tapo sim's state changing, stage by stage.

Each run posts ``bench RUN kitchen_light turn_on`` (or ``turn_off``, alternating) and waits for
the bulb to change and the kernel to settle. A :class:`StatePoller` thread reads ``get_state``
over one kept-open MCP session, polling hard only once the worker model has asked for the tool
(:class:`WorkerTrace` tells it when). The stages come from the kernel process's
:class:`~kernel_bench_harness.Trace` and the models' own stamps (``bench_models``).
"""

from __future__ import annotations

import asyncio
import functools
import json
import os
import threading
from collections.abc import Callable
from concurrent.futures import Future
from pathlib import Path
from typing import Any

import httpx
from kernel_bench_harness import (
    DEVICE,
    SETTLE_TIMEOUT,
    Trace,
    device_host_pid,
    now,
    running_kernel,
    settle,
    summary,
)
from kernel_bench_resources import memory

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


# --- the latency runs --------------------------------------------------------------------------------

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
