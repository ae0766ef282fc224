"""Cross-package tests. This folder goes on sys.path so tests (and workers, via PYTHONPATH) can
import the scripted models in kernel_scripts.py."""

import sys
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import pytest

HERE = str(Path(__file__).parent)
if HERE not in sys.path:
    sys.path.insert(0, HERE)


@pytest.fixture
def walking_dog(api: Any, kernel: Any) -> Callable[[str], Awaitable[dict[str, Any]]]:
    """``await walking_dog(command)``: say ``command`` to the module's kernel (its ``kernel`` and
    ``api`` fixtures) and get the process that holds the dog, once the dog is moving: what every
    stop test needs before it says stop."""
    from e2e_support import walk_the_dog

    async def walk(command: str) -> dict[str, Any]:
        return await walk_the_dog(api, kernel, command)

    return walk
