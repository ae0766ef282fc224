"""The kernel's own tools, called in the kernel's process without a JSON-RPC round trip.

The kernel's tools (``launch_process``, ``stop``, the timers, memory) are a FastMCP server that
the kernel agent mounts in-process (:mod:`rosaos.kernel.tools`). Through pydantic-ai's
:class:`~pydantic_ai.mcp.MCPToolset` alone, every call went over an in-memory MCP session: the
arguments and the result written as JSON-RPC, passed through memory streams and the session's
tasks, and parsed back, inside one process. On the offline command's path that was about 1.5 ms
on 2 cores between the engine's answer and ``launch_process`` starting, before any worker had
its job (issue 26, part 8).

:class:`KernelToolset` keeps the session for listing the tools (cached) and calls each tool with
the server's own :meth:`FastMCP.call_tool`: the same middleware, argument validation and tool
body. It then turns the server's result into what the model reads exactly as the wire path did:
the result a server's ``tools/call`` handler would answer (an error result for an unknown tool
or a :class:`~fastmcp.exceptions.ToolError`), mapped by pydantic-ai's own function, and an error
raised per ``tool_error_behavior``. ``tests/kernel/test_in_process_tools.py`` holds the two paths
to the same results and errors.
"""

from __future__ import annotations

from typing import Any

from fastmcp import FastMCP
from fastmcp.client.client import CallToolResult
from fastmcp.exceptions import DisabledError, FastMCPError, NotFoundError
from mcp import types as mcp_types
from pydantic_ai import ModelRetry, ToolFailed
from pydantic_ai.mcp import _map_mcp_call_tool_result  # the wire path's own mapping
from pydantic_ai.messages import ToolReturnPart

from rosaos.processes.listed_tools import ListedToolset


class KernelToolset(ListedToolset):
    """An MCP toolset over an in-process FastMCP server whose calls skip the MCP session (and whose
    tool definitions are built once per listing, :class:`ListedToolset`)."""

    def __init__(self, server: FastMCP) -> None:
        # "failed": a refused launch comes back as a failed tool result the model reads and acts on;
        # "retry" would count refusals against a retry budget and end the run on the second one.
        super().__init__(server, tool_error_behavior="failed")
        self._server = server

    async def direct_call_tool(
        self,
        name: str,
        args: dict[str, Any],
        *,
        metadata: dict[str, Any] | None = None,
        use_task: bool = False,
    ) -> Any:
        if metadata is not None or use_task:  # not asked for by the kernel; the session handles them
            return await super().direct_call_tool(name, args, metadata=metadata, use_task=use_task)
        result = await call_in_process(self._server, name, args)
        if result.is_error:
            mapped = _map_mcp_call_tool_result(result, prefer_structured=True)
            message = ToolReturnPart(tool_name=name, content=mapped).model_response_str(wrap_if_error=False)
            raise ToolFailed(message or f"Tool {name!r} returned an error")
        return _map_mcp_call_tool_result(result)


async def call_in_process(server: FastMCP, name: str, args: dict[str, Any]) -> CallToolResult:
    """The result ``server`` answers a ``tools/call`` with, without a session.

    Raises :class:`~pydantic_ai.ModelRetry` where the wire path answers a protocol error (an
    exception that is not a tool's error), as pydantic-ai does for one.
    """
    try:
        called = await server.call_tool(name, args)
    except (DisabledError, NotFoundError):
        return _error_result(f"Unknown tool: {name!r}")
    except FastMCPError as error:  # ToolError, argument validation: an error result on the wire
        return _error_result(str(error))
    except Exception as error:
        raise ModelRetry(f"{type(error).__name__}: {error}") from error
    shaped = called.to_mcp_result()
    if isinstance(shaped, mcp_types.CallToolResult):
        return CallToolResult(
            content=shaped.content,
            structured_content=shaped.structured_content,
            meta=shaped.meta,
            is_error=shaped.is_error,
        )
    if isinstance(shaped, tuple):
        content, structured = shaped
        return CallToolResult(content=content, structured_content=structured, meta=None)
    return CallToolResult(content=shaped, structured_content=None, meta=None)


def _error_result(text: str) -> CallToolResult:
    content: list[mcp_types.ContentBlock] = [mcp_types.TextContent(type="text", text=text)]
    return CallToolResult(content=content, structured_content=None, meta=None, is_error=True)
