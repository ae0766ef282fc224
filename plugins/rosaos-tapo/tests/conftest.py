"""Fixtures: a simulated bulb served through FastMCP's in-memory client."""

from __future__ import annotations

import contextlib
from collections.abc import AsyncIterator, Callable
from dataclasses import dataclass
from typing import Any

import pytest
from fastmcp import Client

from rosaos.drivers import DeviceContext
from rosaos_tapo.backend import TapoBackend
from rosaos_tapo.plugin import TapoSettings, sim_backend
from rosaos_tapo.server import build_server


def sim_context(instance: str = "kitchen_light", **sim: Any) -> DeviceContext:
    """The context the hosting layer would build for a ``sim`` instance with this ``sim`` table."""
    return DeviceContext(
        instance=instance,
        description="Ceiling light in the kitchen",
        settings=TapoSettings(),
        backend="sim",
        sim=sim,
    )


@dataclass
class Bulb:
    """A started simulated bulb and a client connected to its MCP server."""

    client: Client[Any]
    backend: TapoBackend

    async def call(self, tool: str, **args: Any) -> dict[str, Any]:
        """Call a tool and return its structured result (the bulb state)."""
        result = await self.client.call_tool(tool, args)
        assert result.structured_content is not None
        return result.structured_content

    async def error(self, tool: str, **args: Any) -> str:
        """Call a tool that must fail and return the error text the model would read."""
        result = await self.client.call_tool(tool, args, raise_on_error=False)
        assert result.is_error, f"{tool}({args}) should have failed"
        return " ".join(getattr(block, "text", "") for block in result.content)


OpenBulb = Callable[..., contextlib.AbstractAsyncContextManager[Bulb]]


@pytest.fixture
def open_bulb() -> OpenBulb:
    """``async with open_bulb(on=False, brightness=40) as bulb:`` starts a sim bulb in that state.

    A context manager rather than an async fixture, so the MCP client is entered and left in
    the same task (anyio requires it).
    """

    @contextlib.asynccontextmanager
    async def open_(**sim: Any) -> AsyncIterator[Bulb]:
        ctx = sim_context(**sim)
        backend = sim_backend(ctx)
        await backend.start()
        try:
            async with Client(build_server(ctx, backend)) as client:
                yield Bulb(client, backend)
        finally:
            await backend.close()

    return open_
