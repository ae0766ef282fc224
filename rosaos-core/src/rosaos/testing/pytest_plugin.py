"""The rosaOS pytest plugin, loaded through the ``pytest11`` entry point of ``rosaos[testing]``.

It registers the ``rosaos_conformance`` marker, marks every check of the conformance kit with it
(``pytest -m rosaos_conformance`` runs only the kit), and names the installed driver plugins in
the report header, so a failing CI log says which versions were under test.

pytest loads this module in every session, so it imports nothing heavy: the kit itself (and
fastmcp) is imported only by test modules that use it.
"""

from __future__ import annotations

from importlib.metadata import entry_points

import pytest

from rosaos.hookspecs import ENTRY_POINT_GROUP

MARKER = "rosaos_conformance"
KIT_CLASS = ("rosaos.testing.conformance", "DriverConformance")


def pytest_configure(config: pytest.Config) -> None:
    """Register the marker, so ``--strict-markers`` accepts it."""
    config.addinivalue_line("markers", f"{MARKER}: a check from the rosaOS driver conformance kit")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Mark the checks inherited from ``DriverConformance`` (not a driver's own tests)."""
    for item in items:
        cls = getattr(item, "cls", None)
        function = getattr(item, "function", None)
        if cls is None or function is None:
            continue
        kit = next((base for base in cls.__mro__ if (base.__module__, base.__name__) == KIT_CLASS), None)
        if kit is not None and function.__name__ in vars(kit):
            item.add_marker(MARKER)


def pytest_report_header(config: pytest.Config) -> list[str]:
    """One header line: the installed driver plugins and their distributions (not imported)."""
    plugins = sorted(
        f"{ep.name} ({ep.dist.name} {ep.dist.version})" if ep.dist else ep.name
        for ep in entry_points(group=ENTRY_POINT_GROUP)
    )
    return ["rosaos driver plugins: " + (", ".join(plugins) or "none")]
