"""Motion tools: timed drives, closed-loop moves and turns, and stop. Limits are enforced by the backend.

No ``from __future__ import annotations`` here: the argument types are built per instance (they
state its limits), and FastMCP must evaluate them where they are defined.
"""

from typing import Annotated, Any

from fastmcp import FastMCP
from pydantic import Field

from rosaos.receipts import safety_report
from rosaos_ros.backend import RosBackend
from rosaos_ros.motion import MotionResult
from rosaos_ros.tools import MOVES, STOPS


def _bounds(low: float, high: float) -> dict[str, Any]:
    """JSON-schema bounds that override the validation bounds in what the model reads."""
    return {"minimum": low, "maximum": high}


def register(mcp: FastMCP, backend: RosBackend) -> None:
    """Add drive, move_distance, rotate and stop, described with this robot's limits."""
    limits, speeds = backend.limits, backend.profile.speeds
    # The schema's bounds are this robot's real limits, so a model that trusts the schema is not
    # refused. Validation keeps a wider sanity bound: a value between the two reaches the safety
    # rule, whose refusal names the limit and the setting that raises it (and is logged as such).
    Linear = Annotated[
        float,
        Field(
            ge=-10,
            le=10,
            description=f"Forward speed in m/s, negative to reverse; at most {limits.linear:g} here.",
            json_schema_extra=_bounds(-limits.linear, limits.linear),
        ),
    ]
    Angular = Annotated[
        float,
        Field(
            ge=-20,
            le=20,
            description=f"Turn rate in rad/s, positive turns left; at most {limits.angular:g} here.",
            json_schema_extra=_bounds(-limits.angular, limits.angular),
        ),
    ]

    async def with_state(result: MotionResult, deadman_before: int) -> dict[str, Any]:
        if result.outcome != "started":
            await backend.state.settle()
        report = {**result.as_dict(), "state": await backend.get_state()}
        # The safety decision, for the activity log's receipts (rosaos.receipts).
        if backend.deadman.fired > deadman_before:
            report |= safety_report(
                "deadman_stop", "deadman", "the command stream went quiet; the robot was stopped"
            )
        elif result.outcome == "stopped":
            report |= safety_report("stopped", "stop", result.detail)
        elif result.outcome == "timed out":
            report |= safety_report("limited", "move timeout", result.detail)
        return report

    @mcp.tool(annotations=MOVES)
    async def drive(
        linear: Linear,
        angular: Angular = 0.0,
        duration: Annotated[
            float,
            Field(gt=0, le=30, description=f"Seconds; at most {backend.profile.max_drive_duration:g} here."),
        ] = 1.0,
        wait: Annotated[
            bool, Field(description="False returns at once; call drive again before the end to keep going.")
        ] = True,
    ) -> dict[str, Any]:
        """Drive with a velocity for a duration, then stop by itself (a deadman: unless renewed).

        Calling drive again before the duration ends renews it with the new velocities. Speeds
        above the robot's limits are refused, not reduced. Prefer move_distance and rotate for
        exact distances and angles.
        """
        fired = backend.deadman.fired
        return await with_state(await backend.drive(linear, angular, duration, wait), fired)

    @mcp.tool(annotations=MOVES)
    async def move_distance(
        meters: Annotated[
            float, Field(ge=-20, le=20, description="Metres straight ahead; negative backs up.")
        ],
        speed: Annotated[
            float | None,
            Field(
                gt=0,
                le=10,
                description=f"m/s; default {min(speeds.linear, limits.linear):g}, at most {limits.linear:g}.",
                json_schema_extra={"maximum": limits.linear},
            ),
        ] = None,
    ) -> dict[str, Any]:
        """Drive a distance straight ahead (or back), measured on odometry, then stop."""
        fired = backend.deadman.fired
        return await with_state(await backend.move_distance(meters, speed), fired)

    @mcp.tool(annotations=MOVES)
    async def rotate(
        degrees: Annotated[
            float,
            Field(
                ge=-720,
                le=720,
                description="Degrees to turn in place: positive left (counter-clockwise), negative right.",
            ),
        ],
        speed: Annotated[
            float | None,
            Field(
                gt=0,
                le=20,
                description=f"rad/s; default {min(speeds.angular, limits.angular):g}, at most {limits.angular:g}.",
                json_schema_extra={"maximum": limits.angular},
            ),
        ] = None,
    ) -> dict[str, Any]:
        """Turn in place by an angle, measured on odometry, then stop. 90 is a quarter turn left, -90 right."""
        fired = backend.deadman.fired
        return await with_state(await backend.rotate(degrees, speed), fired)

    @mcp.tool(annotations=STOPS)
    async def stop() -> dict[str, Any]:
        """Stop now: zero velocity, end the running drive or move, and cancel running action goals."""
        stopped = await backend.stop()
        await backend.state.settle()
        return {**stopped, "state": await backend.get_state()}
