"""Showing a benchmark run to people: the progress bar while it runs, then a table per file.

The table has one row per task: its result, the latency from posting the sentence to settling,
the model requests and tool calls it took, and what differed (expected vs actual) or why it is
pending. Below each file and at the end: success rate, latency p50/p95, and pass^k.
"""

from __future__ import annotations

from types import TracebackType

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    SpinnerColumn,
    TextColumn,
    TimeElapsedColumn,
)
from rich.table import Table

from rosaos.bench.expect import describe
from rosaos.bench.results import BenchResult, FileResult, Summary, TaskResult, TrialResult, percentile

STYLES = {"pass": "green", "fail": "red", "error": "bold red", "pending": "yellow"}


class ProgressBar:
    """A ``BenchProgress`` drawn with rich on stderr; invisible when stderr is not a terminal."""

    def __init__(self, console: Console, total: int, repeat: int) -> None:
        self._repeat = repeat
        self._progress = Progress(
            SpinnerColumn(),
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TimeElapsedColumn(),
            console=console,
            transient=True,
        )
        self._bar = self._progress.add_task("starting", total=total)
        self._failed = 0

    def __enter__(self) -> ProgressBar:
        self._progress.start()
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self._progress.stop()

    def started(self, task_id: str, trial: int) -> None:
        suffix = f" (trial {trial}/{self._repeat})" if self._repeat > 1 else ""
        failed = f" · {self._failed} not passed" if self._failed else ""
        self._progress.update(self._bar, description=f"{task_id}{suffix}{failed}")

    def finished(self, task_id: str, result: TrialResult | None) -> None:
        if result is not None and not result.passed:
            self._failed += 1
        self._progress.advance(self._bar, 1 if result is not None else self._repeat)


def print_report(result: BenchResult, console: Console) -> None:
    """The per-file tables and the summaries."""
    console.print(f"Model: {result.model}", markup=False)
    for file in result.files:
        console.print()
        console.print(_table(file))
        if file.error:
            console.print(f"  {file.error}", style="red", markup=False)
        console.print(f"  {file.name}: {summary_line(file.summary)}", markup=False)
        if result.repeat > 1 and file.summary.pass_hat_k:
            console.print(f"  {pass_hat_k_line(file.summary)}", markup=False)
    console.print()
    console.print(f"Overall: {summary_line(result.summary)}", style="bold", markup=False)
    if result.repeat > 1 and result.summary.pass_hat_k:
        console.print(f"  {pass_hat_k_line(result.summary)}", markup=False)
    console.print(f"  Run data and log: {result.data_dir}", style="dim", markup=False)


def _table(file: FileResult) -> Table:
    table = Table(title=f"{file.name}  ({file.path})", title_justify="left", expand=False)
    table.add_column("Task", no_wrap=True)
    table.add_column("Result", no_wrap=True)
    table.add_column("Latency", justify="right", no_wrap=True)
    table.add_column("Model calls", justify="right")
    table.add_column("Tool calls", justify="right")
    table.add_column("Differences (expected vs actual) / reason", overflow="fold")
    for task in file.tasks:
        status = task.status
        style = STYLES.get(status, "green" if task.passes == len(task.trials) else "red")
        table.add_row(
            task.id,
            f"[{style}]{status}[/]",
            _latency(task),
            _mean(task, "model_calls"),
            _mean(task, "tool_calls"),
            _details(task),
        )
    return table


def _latency(task: TaskResult) -> str:
    value = percentile((t.latency_s for t in task.trials if t.latency_s is not None), 0.5)
    return "-" if value is None else f"{value:.2f} s"


def _mean(task: TaskResult, field: str) -> str:
    if not task.trials:
        return "-"
    values = [getattr(trial, field) for trial in task.trials]
    mean = sum(values) / len(values)
    return f"{mean:.0f}" if mean == int(mean) else f"{mean:.1f}"


def _details(task: TaskResult) -> str:
    """Pending reason, or the first failing trial's differences / reason; escaped for rich."""
    if task.pending is not None:
        return _escape(task.pending)
    failing = next((t for t in task.trials if not t.passed), None)
    if failing is None:
        return ""
    if failing.differences or failing.reply_ok is False:
        lines = [
            f"{d.device}.{d.key}: {_want(d.expected, d.rule)} vs {d.actual!r}" for d in failing.differences
        ]
        if failing.reply_ok is False:
            lines.append(f"reply: no match in {failing.replies!r}")
        prefix = [failing.reason.split(";")[0]] if failing.status == "error" and failing.reason else []
        return _escape("\n".join(prefix + lines))
    return _escape(failing.reason or failing.status)


def _want(expected: object, rule: str) -> str:
    return f"unchanged {expected!r}" if rule == "unchanged" else describe(expected)


def summary_line(summary: Summary) -> str:
    """``13/16 passed (81.2%) · 4 pending · latency p50 0.21 s, p95 0.45 s``."""
    if summary.success_rate is None:
        ran = "nothing ran"
    else:
        ran = f"{summary.passed}/{summary.trials} passed ({summary.success_rate:.1%})"
    parts = [ran]
    if summary.pending:
        parts.append(f"{summary.pending} pending (not counted)")
    if summary.latency_p50_s is not None and summary.latency_p95_s is not None:
        parts.append(f"latency p50 {summary.latency_p50_s:.2f} s, p95 {summary.latency_p95_s:.2f} s")
    return " · ".join(parts)


def pass_hat_k_line(summary: Summary) -> str:
    """``pass^1 0.92 · pass^2 0.88 · pass^3 0.85``."""
    return " · ".join(f"pass^{k} {value:.3f}" for k, value in summary.pass_hat_k.items())


def _escape(text: str) -> str:
    return text.replace("[", r"\[")
