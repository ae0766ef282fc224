"""Fixtures: a simulated player served through FastMCP's in-memory client."""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from typing import Any

import pytest
from fastmcp import Client

from rosaos.drivers import DeviceContext
from rosaos_spotify.plugin import sim_backend
from rosaos_spotify.server import build_server
from rosaos_spotify.settings import SpotifySettings
from rosaos_spotify.simulator import SimBackend

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


def sim_context(instance: str = "spotify", **sim: Any) -> DeviceContext:
    """The context the hosting layer would build for a ``sim`` instance with this ``sim`` table."""
    return DeviceContext(
        instance=instance,
        description="Music on the living room speaker",
        settings=SpotifySettings(),
        backend="sim",
        sim=sim,
    )


@dataclass
class Player:
    """A started simulated player and a client connected to its MCP server."""

    client: Client[Any]
    backend: SimBackend

    async def call(self, tool: str, **args: Any) -> dict[str, Any]:
        """Call a tool and return its structured result."""
        result = await self.client.call_tool(tool, args)
        assert result.structured_content is not None
        return result.structured_content

    async def state(self) -> dict[str, Any]:
        """``get_state``'s answer."""
        return await self.call("get_state")

    async def error(self, tool: str, **args: Any) -> str:
        """Call a tool that must fail and return the error text the model would read."""
        result = await self.client.call_tool(tool, args, raise_on_error=False)
        assert result.is_error, f"{tool}({args}) should have failed"
        return " ".join(getattr(block, "text", "") for block in result.content)


@pytest.fixture
def home_catalog() -> list[dict[str, str]]:
    """The six-track catalog of the bench's home world."""
    return [dict(entry) for entry in HOME_CATALOG]


OpenPlayer = Callable[..., contextlib.AbstractAsyncContextManager[Player]]


@pytest.fixture
def open_player() -> OpenPlayer:
    """``async with open_player(volume=40, catalog=...) as player:`` starts a sim player in that state.

    A context manager rather than an async fixture, so the MCP client is entered and left in
    the same task (anyio requires it).
    """

    @contextlib.asynccontextmanager
    async def open_(**sim: Any) -> AsyncIterator[Player]:
        ctx = sim_context(**sim)
        backend = sim_backend(ctx)
        assert isinstance(backend, SimBackend)
        await backend.start()
        try:
            async with Client(build_server(ctx, backend)) as client:
                yield Player(client, backend)
        finally:
            await backend.close()

    return open_
