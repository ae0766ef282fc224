"""Test helper modules are imported by bare name (their folder goes on ``sys.path`` from a conftest),
so two helpers with the same file name shadow each other: whichever is imported first wins, and the
other folder's tests fail to import depending on collection order. Keep every name unique."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
TEST_ROOTS = [REPO / "tests", REPO / "rosaos-core" / "tests", *sorted((REPO / "plugins").glob("*/tests"))]


def helper_modules() -> dict[str, list[Path]]:
    """Every non-test, non-conftest module under the test folders, by file name."""
    found: dict[str, list[Path]] = defaultdict(list)
    for root in TEST_ROOTS:
        for path in root.rglob("*.py"):
            if path.name.startswith("test_") or path.name in {"conftest.py", "__init__.py"}:
                continue
            found[path.name].append(path.relative_to(REPO))
    return found


def test_the_scan_sees_the_helpers() -> None:
    assert "kernel_scripts.py" in helper_modules()


def test_helper_module_names_are_unique() -> None:
    clashes = {name: paths for name, paths in helper_modules().items() if len(paths) > 1}
    assert not clashes, f"helper modules sharing a name (rename one): {clashes}"
