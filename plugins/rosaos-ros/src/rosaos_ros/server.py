"""The MCP server of one ``ros`` instance: the tools of :mod:`rosaos_ros.tools` on a started backend."""

from __future__ import annotations

from fastmcp import FastMCP

from rosaos.drivers import DeviceContext
from rosaos_ros.backend import RosBackend
from rosaos_ros.tools import actions, interfaces, motion, perception, robot, search, services, topics


def build_server(ctx: DeviceContext, backend: RosBackend) -> FastMCP:
    """Build the FastMCP server for one robot instance."""
    profile, limits, policy = backend.profile, backend.limits, backend.policy
    allowed = "; ".join(f"{kind}: {', '.join(policy.allowed(kind)) or 'nothing'}" for kind in policy.allow)
    mcp = FastMCP(
        name=ctx.instance,
        instructions=(
            f"{ctx.description} ({profile.title}, ROS 2 over rosbridge). Limits: {limits.linear:g} m/s, "
            f"{limits.angular:g} rad/s. Allowed besides motion: {allowed}."
        ),
    )
    robot.register(mcp, backend)
    perception.register(mcp, backend)
    search.register(mcp, backend)
    motion.register(mcp, backend)
    topics.register(mcp, backend)
    services.register(mcp, backend)
    actions.register(mcp, backend)
    interfaces.register(mcp, backend)
    return mcp
