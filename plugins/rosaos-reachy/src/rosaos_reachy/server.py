"""The MCP server of a ``reachy`` instance. Only ``get_state`` until the driver is implemented."""

from __future__ import annotations

from typing import Any

from fastmcp import FastMCP

from rosaos.drivers import DeviceBackend, DeviceContext

READ_ONLY: dict[str, Any] = {"readOnlyHint": True, "destructiveHint": False, "idempotentHint": True}


def build_server(ctx: DeviceContext, backend: DeviceBackend) -> FastMCP:
    """Build the FastMCP server for one instance: ``get_state`` says the driver is a placeholder."""
    mcp = FastMCP(name=ctx.instance, instructions=f"{ctx.description} (Pollen Robotics Reachy Mini).")

    @mcp.tool(annotations=READ_ONLY)
    async def get_state() -> dict[str, Any]:
        """Read the device state. For now: only that the driver is not implemented yet."""
        return {"implemented": False, "driver": "reachy"}

    return mcp
