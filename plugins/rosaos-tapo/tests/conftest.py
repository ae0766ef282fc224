"""Fixtures: a simulated bulb served through FastMCP's in-memory client."""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import Any

import pytest

from rosaos.testing import SimDevice, open_sim_device
from rosaos_tapo.plugin import SPEC

OpenBulb = Callable[..., contextlib.AbstractAsyncContextManager[SimDevice]]


@pytest.fixture
def open_bulb() -> OpenBulb:
    """``async with open_bulb(on=False, brightness=40) as bulb:`` starts the ``kitchen_light``
    sim bulb in that state (the simulator's defaults for the rest).

    A context manager rather than an async fixture, so the MCP client is entered and left in
    the same task (anyio requires it).
    """

    def open_(**sim: Any) -> contextlib.AbstractAsyncContextManager[SimDevice]:
        return open_sim_device(SPEC, "kitchen_light", sim=sim)

    return open_
