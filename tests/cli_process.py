"""Helpers for tests that run the real ``rosaos`` command as a subprocess and kill it."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

ROSAOS = Path(sys.executable).with_name("rosaos")
"""The ``rosaos`` console script of the environment running the tests."""


def line_matching(process: subprocess.Popen[str], pattern: str, timeout: float = 120) -> re.Match[str]:
    """Read ``process``'s output until a line matches ``pattern``; kill it and fail with what it said."""
    assert process.stdout is not None
    seen = []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = process.stdout.readline()
        if not line:
            break
        seen.append(line)
        if match := re.search(pattern, line):
            return match
    process.kill()
    raise AssertionError(f"no line matching {pattern!r}:\n" + "".join(seen))
