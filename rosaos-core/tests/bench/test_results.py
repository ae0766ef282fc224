"""The numbers of a run: success rate, latency percentiles and tau-bench's pass^k."""

from __future__ import annotations

import pytest

from rosaos.bench.results import Summary, TaskResult, TrialResult, TrialStatus, pass_hat_k, percentile


def task(*statuses: TrialStatus, latency: float = 1.0) -> TaskResult:
    trials = [TrialResult(status=status, latency_s=latency) for status in statuses]
    return TaskResult(id="t", say="s", trials=trials)


def test_pass_hat_k_is_the_chance_that_all_k_trials_pass() -> None:
    # 2 of 4 passes: pass^1 = 2/4, pass^2 = C(2,2)/C(4,2) = 1/6, pass^3 = 0.
    result = pass_hat_k([(2, 4)])
    assert result[1] == pytest.approx(0.5)
    assert result[2] == pytest.approx(1 / 6)
    assert result[3] == 0
    assert result[4] == 0


def test_pass_hat_k_averages_over_tasks() -> None:
    assert pass_hat_k([(3, 3), (0, 3)]) == {1: 0.5, 2: 0.5, 3: 0.5}


def test_percentile_interpolates_between_ranks() -> None:
    assert percentile([1.0, 2.0, 3.0, 4.0], 0.5) == 2.5
    assert percentile([1.0, 2.0, 3.0, 4.0], 0.95) == pytest.approx(3.85)
    assert percentile([], 0.5) is None


def test_pending_tasks_are_left_out_of_the_success_rate() -> None:
    pending = TaskResult(id="p", say="s", pending="reachy: driver 'reachy' not implemented")
    summary = Summary.of([task("pass"), task("fail"), pending])
    assert (summary.tasks, summary.pending, summary.success_rate) == (2, 1, 0.5)


def test_errors_count_as_failures_and_have_no_latency() -> None:
    errored = TaskResult(id="e", say="s", trials=[TrialResult(status="error", reason="did not settle")])
    summary = Summary.of([task("pass", latency=0.2), errored])
    assert summary.success_rate == 0.5
    assert summary.latency_p50_s == 0.2


def test_several_trials_show_as_passes_over_trials() -> None:
    assert task("pass", "fail", "pass").status == "2/3"
