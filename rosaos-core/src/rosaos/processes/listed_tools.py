"""An MCP toolset whose tool definitions are built once per listing of the server's tools.

pydantic-ai's :class:`~pydantic_ai.mcp.MCPToolset` caches a server's tool list (until the server
says it changed), but its ``get_tools`` validated every tool's input and output schema and built
its definition again on each call: for the kernel, on every turn; for a worker, on every job, a
fixed cost in front of the first device call of a light switch (issue 26, part 8).
"""

from __future__ import annotations

from typing import Any

from mcp import types as mcp_types
from pydantic_ai import RunContext
from pydantic_ai.mcp import MCPToolset
from pydantic_ai.toolsets import ToolsetTool


class ListedToolset(MCPToolset[Any]):
    """:class:`MCPToolset` that keeps what ``get_tools`` built for the same cached list.

    Built again when pydantic-ai lists the tools anew (a ``tools/list_changed`` notification, a
    new session) or a run asks with another retry budget, the only part of the run context the
    tools depend on.
    """

    _built: tuple[list[mcp_types.Tool], int, dict[str, ToolsetTool[Any]]] | None = None

    async def get_tools(self, ctx: RunContext[Any]) -> dict[str, ToolsetTool[Any]]:
        listed = await self.list_tools()
        built = self._built
        if built is None or built[0] is not listed or built[1] != ctx.max_retries:
            built = self._built = (listed, ctx.max_retries, await super().get_tools(ctx))
        return dict(built[2])
