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
   load-generator process posts ``--events`` chats from ``--clients`` concurrent clients (raw
   HTTP/1.1 on kept-open sockets; ``--load-client httpx`` for the httpx clients used before);
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

The parts live beside this script, by role: ``kernel_bench_harness`` (the kernel under test),
``kernel_bench_latency``, ``kernel_bench_throughput`` (and the load generator this script runs as
with a hidden flag), ``kernel_bench_resources`` (memory, start-up) and ``kernel_bench_report``.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from kernel_bench_harness import EXPERIMENTS, FORK_SERVER, HERE, enable_tcp_nodelay, now
from kernel_bench_latency import latency
from kernel_bench_report import report
from kernel_bench_resources import machine, worker_start
from kernel_bench_throughput import load_generator, raw_load_generator, throughput

DEFAULT_JSON = HERE / "results" / "kernel.json"
SECTIONS = ("warm", "cold", "throughput", "worker-start")


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
                    options.events, options.clients, options.round_trips, options.load_client
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
        "--load-client",
        choices=("raw", "httpx"),
        default="raw",
        help="the throughput test's clients: raw HTTP/1.1 sockets (default) or httpx (see the README)",
    )
    parser.add_argument(
        "--load-generator", nargs=4, metavar=("URL", "COUNT", "CLIENTS", "KIND"), help=argparse.SUPPRESS
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
        url, count, clients, kind = options.load_generator
        token = sys.stdin.read().strip()
        generate = raw_load_generator if kind == "raw" else load_generator
        print(json.dumps(asyncio.run(generate(url, int(count), int(clients), token))))
        return
    results = asyncio.run(run(options))
    results["json"] = str(options.json)
    options.json.parent.mkdir(parents=True, exist_ok=True)
    options.json.write_text(json.dumps(results, indent=2, default=str) + "\n", encoding="utf-8")
    report(results)


if __name__ == "__main__":
    main()
