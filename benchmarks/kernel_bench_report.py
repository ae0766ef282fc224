"""The tables ``kernel.py`` prints (rich) from its results, the same dictionary it writes as JSON.

One table per part that ran: latency by pool and stage, throughput, then memory and start-up.
"""

from __future__ import annotations

import statistics
import sys
from typing import Any

from kernel_bench_latency import STAGES, TOTALS


def report(results: dict[str, Any]) -> None:
    """Print the tables for ``results`` and where its JSON went."""
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
            title=f"Throughput: {t['events']} events from {t['clients']} {t.get('load_client', 'httpx')} clients, no-op kernel model"
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
        if "kernel_cpu_ms_per_event" in t:
            table.add_row(
                "kernel process CPU per event (API to handled), ms", f"{t['kernel_cpu_ms_per_event']:.2f}"
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
