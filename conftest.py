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
the modules with slow tests first (:func:`_slow_modules_first`).
"""

from __future__ import annotations

from pathlib import Path

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


def _slow_modules_first(items: list[pytest.Item]) -> None:
    """Put the modules with an e2e test first, then browser, then slow ones, then the rest; each
    module's tests keep their order.

    Under xdist (``--dist loadscope --no-loadscope-reorder``, see ``scripts/test``) modules are
    handed to the workers in this order. The slow modules are few and long (a real ``rosaos up``
    each, a minute or more for some); collected last, as ``tests/`` is, the last of them ran alone
    while the other worker had nothing left, and xdist's own reordering (most tests first) put them
    last too. Longest first leaves the many short modules to fill in around them.
    """
    rank: dict[str, int] = {}
    for item in items:
        name = getattr(getattr(item, "module", None), "__name__", "")
        tier = next((i for i, t in enumerate(SLOW_TIERS) if item.get_closest_marker(t)), len(SLOW_TIERS))
        rank[name] = min(rank.get(name, tier), tier)
    items.sort(key=lambda item: rank[getattr(getattr(item, "module", None), "__name__", "")])
