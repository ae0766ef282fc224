"""Test folders are packages named from the rootdir, so their modules may share file names.

pytest imports every test file with ``--import-mode=importlib``. A folder without ``__init__.py``
gets a package named after its path from the rootdir (``plugins.rosaos-tapo.tests``), so the four
plugins' ``test_plugin.py`` are four modules, and a test imports its folder's helpers relatively
(``from .kernel_support import TestRuntime``) with no ``sys.path`` changes. An ``__init__.py``
would name the package after the folder alone: every plugin's would be ``tests``, and the second
``tests.test_plugin`` would silently be the first one again.
"""

from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FOLDER_ON_PATH = re.compile(r"sys\.path\.(insert|append)\([^)]*(HERE|__file__)")
TEST_ROOTS = [REPO / "tests", REPO / "rosaos-core" / "tests", *sorted((REPO / "plugins").glob("*/tests"))]


def test_the_scan_sees_every_test_folder() -> None:
    assert len(TEST_ROOTS) >= 6 and all(root.is_dir() for root in TEST_ROOTS)


def test_no_test_folder_is_a_regular_package() -> None:
    found = [str(path.relative_to(REPO)) for root in TEST_ROOTS for path in root.rglob("__init__.py")]
    assert not found, f"remove these: the test folder's package would lose its rootdir name: {found}"


def test_the_path_guard_sees_a_folder_put_on_sys_path() -> None:
    assert FOLDER_ON_PATH.search("if HERE not in sys.path:\n    sys.path.insert(0, HERE)\n")
    assert FOLDER_ON_PATH.search("sys.path.append(str(Path(__file__).parent))")
    assert not FOLDER_ON_PATH.search('sys.path.insert(0, str(dest / "src"))')


def test_no_test_puts_its_folder_on_sys_path() -> None:
    """Helpers are imported relatively; a folder on ``sys.path`` would let two same-named helpers
    shadow each other, depending on which test ran first."""
    found = [
        str(path.relative_to(REPO))
        for root in TEST_ROOTS
        for path in root.rglob("*.py")
        if path != Path(__file__).resolve() and FOLDER_ON_PATH.search(path.read_text(encoding="utf-8"))
    ]
    assert not found, f"import the folder's helpers relatively instead: {found}"
