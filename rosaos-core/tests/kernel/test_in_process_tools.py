"""The kernel's tools called in-process answer exactly as over an MCP session.

:class:`~rosaos.kernel.in_process_tools.KernelToolset` skips the in-memory JSON-RPC round trip of
pydantic-ai's ``MCPToolset`` (issue 26, part 8). What the kernel model reads must not change:
each case calls the same FastMCP server through both toolsets and compares the results, or the
failure's class and words.
"""

from __future__ import annotations

from typing import Any

import pytest
from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from pydantic import BaseModel
from pydantic_ai import ModelRetry, RunContext, ToolFailed
from pydantic_ai.mcp import MCPToolset
from pydantic_ai.models.test import TestModel
from pydantic_ai.toolsets import AbstractToolset
from pydantic_ai.usage import RunUsage

from rosaos.kernel.in_process_tools import KernelToolset


class Launched(BaseModel):
    process_id: int
    devices: list[str]


def _server() -> FastMCP:
    server = FastMCP("kernel-like")
    calls: list[str] = []

    @server.tool
    async def launch_process(devices: list[str], task: str | None = None) -> dict[str, Any]:
        """A launch: refused for a device nobody has."""
        calls.append("launch_process")
        if "garage" in devices:
            raise ToolError("unknown device garage; the devices are: kitchen_light")
        return {"process_id": 7, "devices": devices, "state": "running", "task": task}

    @server.tool
    async def list_processes() -> list[dict[str, Any]]:
        """A list: wrapped as ``{"result": [...]}`` in the structured content."""
        return [{"id": 7, "state": "running"}]

    @server.tool
    async def typed() -> Launched:
        """A pydantic model as the return type (an output schema)."""
        return Launched(process_id=3, devices=["lamp"])

    @server.tool
    async def words() -> str:
        """Plain text."""
        return "three timers"

    @server.tool
    async def crash() -> str:
        """A bug in a tool, not a refusal."""
        raise RuntimeError("boom")

    server.calls = calls  # type: ignore[attr-defined]
    return server


async def _call(toolset: AbstractToolset[Any], name: str, args: dict[str, Any]) -> tuple[str, Any]:
    ctx: RunContext[Any] = RunContext(deps=None, model=TestModel(), usage=RunUsage())
    async with toolset:
        tools = await toolset.get_tools(ctx)
        try:
            if name not in tools:  # an unknown name still reaches the server, as a model may send it
                return "ok", await toolset.call_tool(name, args, ctx, next(iter(tools.values())))
            return "ok", await toolset.call_tool(name, args, ctx, tools[name])
        except (ToolFailed, ModelRetry) as failure:
            return type(failure).__name__, failure.message


CASES = [
    ("launch_process", {"devices": ["kitchen_light"], "task": "turn it on"}),
    ("launch_process", {"devices": ["garage"]}),
    ("list_processes", {}),
    ("typed", {}),
    ("words", {}),
    ("crash", {}),
]


@pytest.mark.parametrize(("name", "args"), CASES, ids=[f"{name}-{i}" for i, (name, _) in enumerate(CASES)])
async def test_a_call_in_process_answers_as_the_mcp_session_does(name: str, args: dict[str, Any]) -> None:
    server = _server()
    over_the_session = await _call(MCPToolset(server, tool_error_behavior="failed"), name, args)
    in_process = await _call(KernelToolset(server), name, args)
    assert in_process == over_the_session


async def test_a_refused_launch_is_a_failed_result_with_the_refusal_in_its_words() -> None:
    outcome = await _call(KernelToolset(_server()), "launch_process", {"devices": ["garage"]})
    assert outcome[0] == "ToolFailed" and "unknown device garage" in outcome[1]


async def test_an_unknown_tool_is_named_as_the_session_names_it() -> None:
    server = _server()
    in_process = await _call(KernelToolset(server), "open_garage", {})
    assert in_process == ("ToolFailed", "Unknown tool: 'open_garage'")
    assert in_process == await _call(MCPToolset(server, tool_error_behavior="failed"), "open_garage", {})


async def test_each_call_runs_the_tool_once() -> None:
    server = _server()
    await _call(KernelToolset(server), "launch_process", {"devices": ["kitchen_light"]})
    assert server.calls == ["launch_process"]  # type: ignore[attr-defined]


async def test_the_tools_are_built_once_per_listing_and_as_the_session_lists_them() -> None:
    server = _server()
    ctx: RunContext[Any] = RunContext(deps=None, model=TestModel(), usage=RunUsage())
    kernel_tools = KernelToolset(server)
    async with kernel_tools, MCPToolset(server, tool_error_behavior="failed") as plain:
        first, second = await kernel_tools.get_tools(ctx), await kernel_tools.get_tools(ctx)
        listed = await plain.get_tools(ctx)
    assert all(first[name] is second[name] for name in first), "built again for the same listing"
    assert {name: tool.tool_def for name, tool in first.items()} == {
        name: tool.tool_def for name, tool in listed.items()
    }
