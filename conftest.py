"""Test tiers for the whole workspace, so `./scripts/test --quick` has something to leave out.

Markers are given by where a test lives and what it drives, so a new test file is tiered without
anyone remembering to mark it:

- ``e2e``: every test in the top-level ``tests/`` folder. They start ``rosaos up`` or the CLI as
  subprocesses and cross packages; they are the slowest third of the suite.
- ``browser``: every test in a module that drives headless Chromium through Playwright.
- ``slow``: marked by hand, in the test module (``pytestmark``) or on the test: tests that start OS
  processes (device hosts, worker pools and fork servers, the CLI, a kernel restarted), a physics
  simulator (the Reachy daemon), a speech model over many recordings, or build wheels, venvs,
  the copier template.

``./scripts/test --quick`` runs ``-m "not e2e and not browser and not slow"``; CI runs everything,
the modules with slow tests first (:func:`_slow_modules_first`), and a test with many long
parameters in parts every worker takes (:data:`SPLIT`).
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).parent
E2E_DIR = ROOT / "tests"


def _drives_a_browser(module: object) -> bool:
    return any(name.startswith("playwright") for name in getattr(module, "__dict__", {})) or any(
        getattr(value, "__module__", "").startswith("playwright")
        for value in getattr(module, "__dict__", {}).values()
    )


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Mark each collected test with its tier (see the module docstring)."""
    for item in items:
        path = Path(str(item.path))
        if E2E_DIR in path.parents:
            item.add_marker(pytest.mark.e2e)
        module = getattr(item, "module", None)
        if module is not None and _drives_a_browser(module):
            item.add_marker(pytest.mark.browser)
    _slow_modules_first(items)


SLOW_TIERS = ("e2e", "browser", "slow")

SPLIT: dict[str, int] = {
    "rosaos-core/tests/intents/test_bench_tasks.py::test_bench_task_runs_on_simulators": 4,
    "rosaos-core/tests/intents/test_bench_tasks.py::test_bench_conversations_run_on_one_kernel_per_file": 4,
}
"""Tests handed to the xdist workers in this many parts instead of with their module.

``--dist loadscope`` gives a whole module to one worker, so that its module-scoped set-up runs once.
The bench tasks on simulators were 89 parameters of 2-20 s each (now over 100 robot tasks among
440), mostly a robot simulator moving in real time: 400 s in one module, which one worker ran alone while the other one ran everything else
(and at the end of the run, as the module came after the e2e ones). In parts (every fourth
parameter, so each part has robots, lamps and conversations) they go out first, and each worker's
share of them runs beside the other's; a part costs its module's set-up again (the shared Reachy
daemon, seconds). The conversation files (a kernel each, up to a minute) go out the same way, one
file a part."""


def _slow_modules_first(items: list[pytest.Item]) -> None:
    """Put the modules with an e2e test first, then browser, then slow ones, then the rest; each
    module's tests keep their order.

    Under xdist (``--dist loadscope --no-loadscope-reorder``, see ``scripts/test``) modules are
    handed to the workers in this order. The slow modules are few and long (a real ``rosaos up``
    each, a minute or more for some); collected last, as ``tests/`` is, the last of them ran alone
    while the other workers had nothing left, and xdist's own reordering (most tests first) put them
    last too. Longest first leaves the many short modules to fill in around them.
    """
    rank: dict[str, int] = {}
    for item in items:
        name = getattr(getattr(item, "module", None), "__name__", "")
        tier = next((i for i, t in enumerate(SLOW_TIERS) if item.get_closest_marker(t)), len(SLOW_TIERS))
        rank[name] = min(rank.get(name, tier), tier)

    def order(item: pytest.Item) -> int:
        if _split_function(item.nodeid) in SPLIT:
            return -1  # the longest work of all, in parts that every worker takes (SPLIT)
        return rank[getattr(getattr(item, "module", None), "__name__", "")]

    items.sort(key=order)


def _split_function(nodeid: str) -> str:
    """``path::test`` of a node id, without its parameters."""
    return nodeid.split("[", 1)[0]


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """``--dist loadscope``, with the tests in :data:`SPLIT` handed out in parts of their own."""
    if config.getvalue("dist") != "loadscope":
        return None
    from xdist.scheduler import LoadScopeScheduling

    class SplitScopeScheduling(LoadScopeScheduling):
        """A scope per module (or class), but a :data:`SPLIT` test's parameters go round-robin
        into parts, each a scope of its own."""

        def __init__(self, config: pytest.Config, log: Any = None) -> None:
            super().__init__(config, log)
            self._parts: dict[str, str] = {}
            self._seen: Counter[str] = Counter()

        def _split_scope(self, nodeid: str) -> str:
            function = _split_function(nodeid)
            if function not in SPLIT:
                scope: str = super()._split_scope(nodeid)
                return scope
            if nodeid not in self._parts:  # first met in collection order, so parts are stable
                self._parts[nodeid] = f"{function}[part {self._seen[function] % SPLIT[function] + 1}]"
                self._seen[function] += 1
            return self._parts[nodeid]

    return SplitScopeScheduling(config, log)


_WORKERS: dict[str, list[float]] = {}
"""Per xdist worker, as the controller sees its reports: first start, last stop, seconds in tests."""
_LAST_MODULE: dict[str, str] = {}


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    """Note when each xdist worker ran tests (controller only), for :func:`pytest_terminal_summary`."""
    node = getattr(report, "node", None)
    if node is None or not report.stop:
        return
    name = str(node.gateway.id)
    first, last, busy = _WORKERS.setdefault(name, [report.start, report.stop, 0.0])
    _WORKERS[name] = [min(first, report.start), max(last, report.stop), busy + report.stop - report.start]
    if report.stop >= last:
        _LAST_MODULE[name] = report.nodeid.split("::", 1)[0]


def pytest_terminal_summary(terminalreporter: Any) -> None:
    """How busy each xdist worker was and when it ran out of work: the run is as long as the later
    one, so a worker that ends minutes before the other says the order needs a look (SPLIT,
    :func:`_slow_modules_first`)."""
    if not _WORKERS:
        return
    began = min(first for first, _, _ in _WORKERS.values())
    ends = sorted(last for _, last, _ in _WORKERS.values())
    terminalreporter.section("xdist workers")
    for name, (_, last, busy) in sorted(_WORKERS.items()):
        terminalreporter.write_line(
            f"{name}: {busy:.0f} s in tests, its last test ended at {last - began:.0f} s ({_LAST_MODULE[name]})"
        )
    terminalreporter.write_line(
        f"the first worker out of work waited {ends[-1] - ends[0]:.0f} s for the last"
    )
