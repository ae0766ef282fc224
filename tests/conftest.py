"""Fixtures the cross-package tests share."""

from collections.abc import Awaitable, Callable
from typing import Any

import pytest


@pytest.fixture
def walking_dog(api: Any, kernel: Any) -> Callable[[str], Awaitable[dict[str, Any]]]:
    """``await walking_dog(command)``: say ``command`` to the module's kernel (its ``kernel`` and
    ``api`` fixtures) and get the process that holds the dog, once the dog is moving: what every
    stop test needs before it says stop."""
    from .e2e_support import walk_the_dog

    async def walk(command: str) -> dict[str, Any]:
        return await walk_the_dog(api, kernel, command)

    return walk
