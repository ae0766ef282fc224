"""What a benchmark run produces: per trial, per task, per file and overall; the ``--json`` schema.

Statistics:

- **success rate**: passed trials / trials run. Pending tasks are not run and not counted.
- **latency p50/p95**: from posting the sentence to settling, over the trials that settled
  (a trial that hit the 60 s limit has no latency; it is a failure).
- **pass^k** (tau-bench): the chance that *all* of k independent trials of a task pass,
  estimated from its N trials with c passes as C(c, k) / C(N, k), averaged over tasks, for
  k = 1..N. pass^1 is the success rate; a model that passes a task only sometimes sees pass^k
  fall as k grows.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from datetime import datetime
from math import comb
from typing import Any, Literal

from pydantic import BaseModel, Field

from rosaos.bench.expect import Difference

TrialStatus = Literal["pass", "fail", "error"]
"""``fail``: it ran and settled, and a rule is broken. ``error``: it could not run, or did not settle."""


class DifferenceView(BaseModel):
    """One broken rule: a device key, what was wanted, what ``get_state`` returned."""

    device: str
    key: str
    rule: Literal["expect", "unchanged"]
    expected: Any
    """The ``expect`` value as written (``{gt: 40}``), or the initial value for rule ``unchanged``."""
    actual: Any
    text: str
    """The same in words: ``spotify.volume: expected > 40, got 40``."""

    @classmethod
    def of(cls, difference: Difference) -> DifferenceView:
        return cls(
            device=difference.device,
            key=difference.key,
            rule=difference.rule,
            expected=difference.expected,
            actual=difference.actual if difference.present else None,
            text=str(difference),
        )


class TrialResult(BaseModel):
    """One run of one task."""

    status: TrialStatus
    reason: str | None = None
    """Why it did not pass, in one line."""
    differences: list[DifferenceView] = Field(default_factory=list)
    reply_ok: bool | None = None
    """Whether the ``reply`` regex matched; None when the task has no ``reply``."""
    latency_s: float | None = None
    """Seconds from posting the sentence to settling; None when it did not settle."""
    model_calls: int = 0
    """Model requests: the kernel's, plus every process's (``model_requests`` of its callback)."""
    tool_calls: int = 0
    """Tool calls: the kernel's (``launch_process`` ...), plus every process's MCP tool calls."""
    processes: int = 0
    replies: list[str] = Field(default_factory=list)
    kernel_errors: list[str] = Field(default_factory=list)
    """``error`` updates the kernel published while handling the task."""
    unchecked: dict[str, str] = Field(default_factory=dict)
    """Devices whose state could not be read (placeholder driver, ...), with why."""

    @property
    def passed(self) -> bool:
        return self.status == "pass"


class TaskResult(BaseModel):
    """One task: its trials, or why it is pending."""

    id: str
    say: str
    pending: str | None = None
    """Set when the task cannot run yet: ``driver 'reachy' not implemented``. Not a failure."""
    trials: list[TrialResult] = Field(default_factory=list)

    @property
    def passes(self) -> int:
        return sum(trial.passed for trial in self.trials)

    @property
    def status(self) -> str:
        """``pass``, ``fail``, ``error``, ``pending``, or ``2/3`` over several trials."""
        if self.pending is not None:
            return "pending"
        if len(self.trials) == 1:
            return self.trials[0].status
        return f"{self.passes}/{len(self.trials)}"


class Summary(BaseModel):
    """Success rate, latency and pass^k over some tasks."""

    tasks: int
    """Tasks run (pending ones excluded)."""
    pending: int
    trials: int
    passed: int
    """Trials that passed."""
    success_rate: float | None
    """passed / trials; None when nothing ran."""
    latency_p50_s: float | None
    latency_p95_s: float | None
    pass_hat_k: dict[int, float] = Field(default_factory=dict)
    """k → pass^k, for k = 1..repeat."""

    @classmethod
    def of(cls, tasks: Sequence[TaskResult]) -> Summary:
        ran = [task for task in tasks if task.pending is None and task.trials]
        trials = [trial for task in ran for trial in task.trials]
        latencies = [t.latency_s for t in trials if t.latency_s is not None]
        passed = sum(trial.passed for trial in trials)
        return cls(
            tasks=len(ran),
            pending=sum(task.pending is not None for task in tasks),
            trials=len(trials),
            passed=passed,
            success_rate=passed / len(trials) if trials else None,
            latency_p50_s=percentile(latencies, 0.50),
            latency_p95_s=percentile(latencies, 0.95),
            pass_hat_k=pass_hat_k((task.passes, len(task.trials)) for task in ran),
        )


class FileResult(BaseModel):
    """One task file's world and tasks."""

    path: str
    name: str
    tasks: list[TaskResult]
    summary: Summary
    error: str | None = None
    """Set when the file's world could not be brought up at all; its tasks then show the reason."""


class BenchResult(BaseModel):
    """A whole run: what ``rosaos bench --json`` prints."""

    model: str
    """The kernel model: ``offline local-intent engine``, ``openai:gpt-5.2``, ..."""
    repeat: int
    started_at: datetime
    duration_s: float
    data_dir: str
    """Where the run's event stores and log (``bench.log``) are."""
    files: list[FileResult]
    summary: Summary


def percentile(values: Iterable[float], q: float) -> float | None:
    """The ``q`` quantile (0..1) by linear interpolation between the closest ranks; None if empty."""
    ordered = sorted(values)
    if not ordered:
        return None
    position = (len(ordered) - 1) * q
    low = int(position)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (position - low)


def pass_hat_k(tasks: Iterable[tuple[int, int]]) -> dict[int, float]:
    """tau-bench's pass^k from ``(passes, trials)`` per task, for k = 1..trials (the smallest count).

    Tasks ran the same number of times in one run; should they differ, k stops at the fewest.
    """
    counts = [(c, n) for c, n in tasks if n > 0]
    if not counts:
        return {}
    most = min(n for _, n in counts)
    return {k: sum(comb(c, k) / comb(n, k) for c, n in counts) / len(counts) for k in range(1, most + 1)}
