"""The MCP tools of a ``ros`` instance, one module per ROS primitive or concern.

Each module's ``register(mcp, backend)`` adds its tools to the instance's FastMCP server. Tools
are thin: typed, bounded arguments and a docstring for the model, then one backend call, where
the safety rules live. Annotations are explicit on every tool (see :data:`READ_ONLY` and friends).
"""

from __future__ import annotations

import json
from typing import Annotated, Any

from fastmcp import Context
from pydantic import Field

from rosaos import drivers
from rosaos_ros.goals import FeedbackCallback
from rosaos_ros.messages import summarize

# readOnlyHint/destructiveHint/idempotentHint, set on every tool: clients assume the worst otherwise.
# The shared constants of rosaos.drivers: MOVES (the robot moves, or anything may happen: raw
# publishes, service calls, goals), SETS (a setting; doing it twice is doing it once), STOPS.
READ_ONLY, MOVES, SETS, STOPS = drivers.READ_ONLY, drivers.MOVES, drivers.SETS, drivers.SETS

ROS_NAME = r"^/[A-Za-z0-9_/~]*$"
TopicName = Annotated[
    str,
    Field(min_length=1, max_length=256, pattern=ROS_NAME, description="Absolute topic name, e.g. /odom."),
]
ServiceName = Annotated[
    str,
    Field(min_length=1, max_length=256, pattern=ROS_NAME, description="Absolute service name, e.g. /e_stop."),
]
ActionName = Annotated[
    str,
    Field(min_length=1, max_length=256, pattern=ROS_NAME, description="Absolute action name, e.g. /dock."),
]
NodeName = Annotated[
    str,
    Field(
        min_length=1,
        max_length=256,
        pattern=ROS_NAME,
        description="Absolute node name, e.g. /motion_control.",
    ),
]
ParamName = Annotated[
    str,
    Field(
        min_length=3,
        max_length=256,
        pattern=r"^/[A-Za-z0-9_/~]*:[A-Za-z0-9_.\-/]+$",
        description="Parameter as '/node:name', e.g. /motion_control:max_speed (see list_params).",
    ),
]
TypeName = Annotated[
    str | None,
    Field(
        default=None,
        max_length=256,
        pattern=r"^[A-Za-z0-9_]+/((msg|srv|action)/)?[A-Za-z0-9_]+$",
        description="ROS interface type, e.g. std_msgs/msg/String; omit it to use the type the robot reports.",
    ),
]
Fields = Annotated[
    dict[str, Any],
    Field(description='The fields as a JSON object, nested as in the ROS interface, e.g. {"data": "hello"}.'),
]
ParamValue = bool | int | float | str | list[bool] | list[int] | list[float] | list[str]


def progress_reporter(ctx: Context) -> FeedbackCallback:
    """Forward each action feedback to the MCP client as a progress notification."""

    async def report(count: int, values: dict[str, Any]) -> None:
        await ctx.report_progress(progress=count, message=json.dumps(summarize(values))[:500])

    return report
