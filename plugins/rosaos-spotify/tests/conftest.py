"""Fixtures: a simulated player served through FastMCP's in-memory client."""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import Any

import pytest

from rosaos.testing import SimDevice, open_sim_device
from rosaos_spotify.plugin import SPEC

# The catalog of the bench's home world (../shared/bench/tasks/home.yaml).
HOME_CATALOG = [
    {
        "track": "Clair de Lune",
        "artist": "Claude Debussy",
        "album": "Suite bergamasque",
        "genre": "classical",
    },
    {"track": "Gymnopédie No. 1", "artist": "Erik Satie", "album": "Gymnopédies", "genre": "classical"},
    {"track": "So What", "artist": "Miles Davis", "album": "Kind of Blue", "genre": "jazz"},
    {"track": "Take Five", "artist": "The Dave Brubeck Quartet", "album": "Time Out", "genre": "jazz"},
    {"track": "Here Comes the Sun", "artist": "The Beatles", "album": "Abbey Road", "genre": "rock"},
    {"track": "Bohemian Rhapsody", "artist": "Queen", "album": "A Night at the Opera", "genre": "rock"},
]


@pytest.fixture
def home_catalog() -> list[dict[str, str]]:
    """The six-track catalog of the bench's home world."""
    return [dict(entry) for entry in HOME_CATALOG]


OpenPlayer = Callable[..., contextlib.AbstractAsyncContextManager[SimDevice]]


@pytest.fixture
def open_player() -> OpenPlayer:
    """``async with open_player(volume=40, catalog=...) as player:`` starts the ``spotify`` sim
    player in that state (the simulator's defaults for the rest).

    A context manager rather than an async fixture, so the MCP client is entered and left in
    the same task (anyio requires it).
    """

    def open_(**sim: Any) -> contextlib.AbstractAsyncContextManager[SimDevice]:
        return open_sim_device(SPEC, "spotify", sim=sim)

    return open_
