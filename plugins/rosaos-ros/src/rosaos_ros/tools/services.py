"""Service, parameter and node tools."""

from __future__ import annotations

import asyncio
from typing import Annotated, Any

from fastmcp import FastMCP
from pydantic import Field

from rosaos.drivers import DeviceError
from rosaos_ros.backend import RosBackend
from rosaos_ros.tools import MOVES, READ_ONLY, SETS, Fields, NodeName, ParamName, ParamValue, ServiceName


def register(mcp: FastMCP, backend: RosBackend) -> None:
    """Add the service, parameter and node tools."""
    rosapi = backend.rosapi

    @mcp.tool(annotations=READ_ONLY)
    async def list_services() -> dict[str, Any]:
        """List every service on the robot with its type."""
        names = await rosapi.services()
        types = await asyncio.gather(*(rosapi.service_type(name) for name in names))
        return {"services": [{"name": name, "type": kind} for name, kind in zip(names, types, strict=True)]}

    @mcp.tool(annotations=READ_ONLY)
    async def service_info(service: ServiceName) -> dict[str, Any]:
        """Show a service's type and the node that provides it, and whether this instance may call it."""
        service_type = await rosapi.service_type(service)
        if not service_type:
            raise DeviceError(f"no service {service} on the robot; list_services shows them")
        try:
            backend.policy.check("services", service)
            callable_here = True
        except DeviceError:
            callable_here = False
        return {
            "service": service,
            "type": service_type,
            "node": await rosapi.service_node(service),
            "allowed": callable_here,
        }

    @mcp.tool(annotations=MOVES)
    async def call_service(
        service: ServiceName,
        request: Fields,
        timeout: Annotated[float, Field(gt=0, le=60, description="Seconds to wait for the answer.")] = 10.0,
    ) -> dict[str, Any]:
        """Call an allowed service with a request (its fields as JSON) and return the response.

        Only services on the instance's service allow-list can be called; a refusal says how to
        allow one. Look the request up with service_details(service) first and fill in its
        ``example``; never guess field names.
        """
        return await backend.call_service(service, request, timeout)

    @mcp.tool(annotations=READ_ONLY)
    async def list_params(
        node: Annotated[
            str | None,
            Field(
                default=None,
                max_length=256,
                pattern=r"^/[A-Za-z0-9_/~]*$",
                description="Only this node's, e.g. /oakd.",
            ),
        ] = None,
    ) -> dict[str, Any]:
        """List parameter names ('/node:name'), of every node or of one."""
        names = await rosapi.param_names()
        if node is not None:
            names = [name for name in names if name.startswith(f"{node}:")]
        return {"params": names}

    @mcp.tool(annotations=READ_ONLY)
    async def get_param(name: ParamName) -> dict[str, Any]:
        """Read one parameter's value."""
        return {"name": name, "value": await rosapi.get_param(name)}

    # Destructive: a parameter changes how a node drives the robot (speed limits, controllers), so
    # a "destructive" confirmation rule asks before it like before a move.
    @mcp.tool(annotations=SETS.model_copy(update={"destructive_hint": True}))
    async def set_param(name: ParamName, value: ParamValue) -> dict[str, Any]:
        """Set an allowed parameter (the node keeps its type: give a number for a number).

        Only parameters on the instance's param allow-list can be set; a refusal says how to allow one.
        """
        return await backend.set_param(name, value)

    @mcp.tool(annotations=SETS.model_copy(update={"destructive_hint": True}))
    async def delete_param(name: ParamName) -> dict[str, Any]:
        """Delete (undeclare) an allowed parameter. Most nodes cannot get it back until restarted."""
        return await backend.delete_param(name)

    @mcp.tool(annotations=READ_ONLY)
    async def list_nodes() -> dict[str, Any]:
        """List every node on the robot."""
        return {"nodes": await rosapi.nodes()}

    @mcp.tool(annotations=READ_ONLY)
    async def node_info(node: NodeName) -> dict[str, Any]:
        """Show what a node publishes, subscribes to, and serves."""
        return {"node": node, **await rosapi.node_details(node)}
