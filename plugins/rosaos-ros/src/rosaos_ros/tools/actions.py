"""Action tools: list, send goals with feedback, cancel, status; and the profile's named actions."""

from __future__ import annotations

import asyncio
from typing import Annotated, Any

from fastmcp import Context, FastMCP
from pydantic import Field

from rosaos_ros.backend import RosBackend
from rosaos_ros.tools import MOVES, READ_ONLY, STOPS, ActionName, Fields, TypeName, progress_reporter

GoalId = Annotated[str, Field(min_length=1, max_length=300, description="The goal_id send_goal returned.")]


def register(mcp: FastMCP, backend: RosBackend) -> None:
    """Add the action tools, and one tool per named action of the profile (dock, undock, ...)."""
    rosapi = backend.rosapi

    @mcp.tool(annotations=READ_ONLY)
    async def list_actions() -> dict[str, Any]:
        """List every action server on the robot with its type."""
        names = await rosapi.action_servers()
        types = await asyncio.gather(*(rosapi.action_type(name) for name in names))
        return {
            "actions": [{"name": name, "type": kind or None} for name, kind in zip(names, types, strict=True)]
        }

    @mcp.tool(annotations=MOVES)
    async def send_goal(
        action: ActionName,
        goal: Fields,
        ctx: Context,
        action_type: TypeName = None,
        timeout: Annotated[
            float,
            Field(gt=0, le=600, description="Seconds to wait for the result; the goal is cancelled after."),
        ] = 60.0,
        wait: Annotated[
            bool, Field(description="False returns at once with the goal_id, for goal_status.")
        ] = True,
    ) -> dict[str, Any]:
        """Send a goal to an allowed action and wait for its result, streaming its feedback as progress.

        Look the goal up with action_details(action) first and fill in its ``example``. Only
        actions on the instance's action allow-list accept goals. The result says the status
        (succeeded, canceled, aborted), the last feedback and the result fields.
        """
        return await backend.send_goal(action, goal, action_type, timeout, wait, progress_reporter(ctx))

    @mcp.tool(annotations=STOPS)
    async def cancel_goal(goal_id: GoalId) -> dict[str, Any]:
        """Cancel a running goal and report its final status."""
        return (await backend.goals.cancel(goal_id)).as_dict()

    @mcp.tool(annotations=READ_ONLY)
    async def goal_status(
        goal_id: Annotated[
            str | None, Field(default=None, max_length=300, description="Omit for every recent goal.")
        ] = None,
    ) -> dict[str, Any]:
        """Report a goal's status, feedback count, last feedback and result (or every recent goal's)."""
        if goal_id is not None:
            return backend.goals.get(goal_id).as_dict()
        return {"goals": [record.as_dict() for record in backend.goals.goals.values()]}

    for name, named in backend.profile.actions.items():
        _register_named_action(mcp, backend, name, named.description, named.action)


def _register_named_action(
    mcp: FastMCP, backend: RosBackend, name: str, description: str, action: str
) -> None:
    async def run_named_action(ctx: Context) -> dict[str, Any]:
        return await backend.run_named_action(name, progress_reporter(ctx))

    mcp.tool(
        run_named_action,
        name=name,
        description=f"{description} (The {action} action; feedback streams as progress; returns the state after.)",
        annotations=MOVES,
    )
