"""Motion tools: timed drives, closed-loop moves and turns, and stop. Limits are enforced by the backend.

No ``from __future__ import annotations`` here: the argument types are built per instance (they
state its limits), and FastMCP must evaluate them where they are defined.
"""

from typing import Annotated, Any

from fastmcp import Context, FastMCP
from pydantic import Field

from rosaos.receipts import safety_report
from rosaos_ros.backend import RosBackend
from rosaos_ros.motion import MotionResult
from rosaos_ros.tools import MOVES, READ_ONLY, STOPS, progress_reporter

Coordinate = Annotated[
    float,
    Field(ge=-1000, le=1000, allow_inf_nan=False, description="Metres in the frame get_pose reports."),
]

MIN_LINEAR_SPEED = 0.02
"""m/s: slower than this a move of metres takes minutes, or, at 1e-9, for ever (its timeout with it)."""
MIN_ANGULAR_SPEED = 0.05
"""rad/s: the same floor for turns."""


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
                ge=MIN_LINEAR_SPEED,
                le=10,
                allow_inf_nan=False,
                description=(
                    f"m/s, at least {MIN_LINEAR_SPEED:g}; default {min(speeds.linear, limits.linear):g}, "
                    f"at most {limits.linear:g}."
                ),
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
                ge=MIN_ANGULAR_SPEED,
                le=20,
                allow_inf_nan=False,
                description=(
                    f"rad/s, at least {MIN_ANGULAR_SPEED:g}; default {min(speeds.angular, limits.angular):g}, "
                    f"at most {limits.angular:g}."
                ),
                json_schema_extra={"maximum": limits.angular},
            ),
        ] = None,
    ) -> dict[str, Any]:
        """Turn in place by an angle, measured on odometry, then stop. 90 is a quarter turn left, -90 right."""
        fired = backend.deadman.fired
        return await with_state(await backend.rotate(degrees, speed), fired)

    @mcp.tool(annotations=READ_ONLY)
    async def get_pose() -> dict[str, Any]:
        """Where the robot is: x, y (m), yaw (rad), the frame (map or odom) and its anchor.

        The anchor names the frame's instance: the map's file, or this driver run's odometry. A
        pose saved with it can be given back to go_to, which refuses it in any other frame.
        """
        return await backend.get_pose()

    @mcp.tool(annotations=MOVES)
    async def go_to(
        x: Coordinate,
        y: Coordinate,
        ctx: Context,
        yaw: Annotated[
            float | None,
            Field(
                ge=-2 * 3.1416,
                le=2 * 3.1416,
                allow_inf_nan=False,
                description="Final heading in radians (0 along +x, counter-clockwise); omit to arrive "
                "facing the way the robot drove.",
            ),
        ] = None,
        frame_anchor: Annotated[
            str | None,
            Field(
                max_length=300,
                description="The anchor get_pose gave when the goal was saved: go_to refuses the goal "
                "if the robot is in another frame now. Omit for coordinates in the current frame.",
            ),
        ] = None,
    ) -> dict[str, Any]:
        """Go to a pose: on a map with Nav2 it plans around obstacles; feedback streams as progress.

        Without a map (no Nav2 in the profile) it turns, drives straight on odometry and turns,
        avoiding nothing. stop cancels it. Returns the pose reached and how far from the goal.
        """
        fired = backend.deadman.fired
        result = await backend.go_to(x, y, yaw, frame_anchor, progress_reporter(ctx))
        report = {**result, "state": await backend.get_state()}
        if backend.deadman.fired > fired:
            report |= safety_report(
                "deadman_stop", "deadman", "the command stream went quiet; the robot was stopped"
            )
        return report

    @mcp.tool(annotations=STOPS)
    async def stop() -> dict[str, Any]:
        """Stop now: zero velocity, end the running drive or move, and cancel running action goals."""
        stopped = await backend.stop()
        await backend.state.settle()
        return {**stopped, "state": await backend.get_state()}
