"""The motion tools of a Reachy Mini: head, body, antennas, emotions, dances, wake and sleep.

Every motion interrupts the one under way (the latest request wins). Poses return once reached;
emotions and dances return when they start, unless ``wait`` is set.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from fastmcp import FastMCP
from pydantic import Field

from rosaos_reachy.annotations import ACT, READ_ONLY, SET
from rosaos_reachy.backend import (
    LOOK_PITCH,
    LOOK_YAW,
    MAX_BODY_YAW,
    MAX_HEAD_PITCH,
    MAX_HEAD_ROLL,
    MAX_HEAD_YAW,
    ReachyBackend,
)
from rosaos_reachy.state import MotionReport

Direction = Literal["left", "right", "up", "down", "front"]
Yaw = Annotated[
    float | None,
    Field(
        ge=-MAX_HEAD_YAW,
        le=MAX_HEAD_YAW,
        description="Degrees to turn the head, + left, relative to the body.",
    ),
]
Pitch = Annotated[
    float | None,
    Field(ge=-MAX_HEAD_PITCH, le=MAX_HEAD_PITCH, description="Degrees to tilt the head, + down, - up."),
]
Roll = Annotated[
    float | None,
    Field(ge=-MAX_HEAD_ROLL, le=MAX_HEAD_ROLL, description="Degrees to tilt the head sideways, + right."),
]
Metres = Annotated[float, Field(ge=-3.0, le=3.0)]
BodyYaw = Annotated[
    float,
    Field(
        ge=-MAX_BODY_YAW, le=MAX_BODY_YAW, description="Body angle in degrees from facing forward, + left."
    ),
]
Antenna = Annotated[
    float,
    Field(ge=-175.0, le=175.0, description="Degrees; ~10 is rest, negative tips forward, 175 folds it down."),
]
MoveName = Annotated[str, Field(min_length=1, max_length=60, description="A name list_emotions gives.")]
Wait = Annotated[bool, Field(description="Return only when it has finished (default: as it starts).")]

DIRECTIONS: dict[str, tuple[float, float]] = {
    "left": (LOOK_YAW, 0.0),
    "right": (-LOOK_YAW, 0.0),
    "up": (0.0, -LOOK_PITCH),
    "down": (0.0, LOOK_PITCH),
    "front": (0.0, 0.0),
}


def register(mcp: FastMCP, backend: ReachyBackend) -> None:
    """Add the motion tools to ``mcp``."""

    @mcp.tool(annotations=SET)
    async def look(
        direction: Direction | None = None, yaw: Yaw = None, pitch: Pitch = None, roll: Roll = None
    ) -> MotionReport:
        """Turn the head: by ``direction`` (left, right, up, down, front), or by angles in degrees.

        "left"/"right" turn 30°, "up"/"down" tilt 20°. Angles given override the direction's;
        angles not given are 0 (level, facing where the body faces). Returns once the head is there.
        """
        base_yaw, base_pitch = DIRECTIONS[direction or "front"]
        what: str = direction or "ahead"
        if direction is None and (yaw or pitch or roll):
            what = f"yaw {yaw or 0:+.0f}°, pitch {pitch or 0:+.0f}°, roll {roll or 0:+.0f}°"
        return await backend.look(
            base_yaw if yaw is None else yaw,
            base_pitch if pitch is None else pitch,
            0.0 if roll is None else roll,
            what,
        )

    @mcp.tool(annotations=SET)
    async def look_at_point(x: Metres, y: Metres, z: Metres) -> MotionReport:
        """Look at a point in space, in metres from the head's neutral centre: x forward, y left, z up.

        E.g. (0.5, 0, -0.2) is the desk half a metre ahead. Points beyond the head's reach
        (more than 60° aside) are refused: rotate_body toward them first.
        """
        return await backend.look_at_point(x, y, z)

    @mcp.tool(annotations=SET)
    async def reset_head() -> MotionReport:
        """Bring the head back to neutral: level, facing where the body faces."""
        return await backend.look(0.0, 0.0, 0.0, "ahead")

    @mcp.tool(annotations=SET)
    async def rotate_body(degrees: BodyYaw) -> MotionReport:
        """Turn the body (the base's turntable) to an angle from facing forward, + left; the head
        turns with it. 0 faces forward again. Absolute, not relative: read body_yaw to add to it."""
        return await backend.rotate_body(degrees)

    @mcp.tool(annotations=SET)
    async def move_antennas(left: Antenna, right: Antenna) -> MotionReport:
        """Set both antennas, in degrees. Equal values make a symmetric pose: about 10 is the rest
        pose, -30 perks them up and forward, 60-90 droops them back."""
        return await backend.move_antennas(left, right)

    @mcp.tool(annotations=ACT)
    async def play_emotion(name: MoveName, wait: Wait = False) -> MotionReport:
        """Express an emotion with head and antennas: happy, sad, surprised, curious, yes (nod),
        no (shake), confused, excited, angry, thinking, love, laugh, sleepy... (list_emotions has
        them all). The robot returns to its pose afterwards."""
        return await backend.play("emotions", name, wait)

    @mcp.tool(annotations=READ_ONLY)
    async def list_emotions() -> dict[str, Any]:
        """The emotions and dances this robot can play, and where they come from: Pollen's
        recorded dataset when it is cached on this computer, else the driver's built-in set."""
        return backend.moves.listing()

    @mcp.tool(annotations=ACT)
    async def dance(name: MoveName | None = None, wait: Wait = False) -> MotionReport:
        """Dance: groove (default), sway or robot, or a recorded dance if list_emotions has them."""
        return await backend.play("dances", name or "groove", wait)

    @mcp.tool(annotations=SET)
    async def stop_motion() -> MotionReport:
        """Stop moving at once and hold the current pose. Speech goes on."""
        return await backend.stop_motion()

    @mcp.tool(annotations=SET)
    async def wake_up() -> MotionReport:
        """Wake up: motors on, head up to the rest pose, antennas up. Motion tools also wake it."""
        return await backend.wake_up()

    @mcp.tool(annotations=SET)
    async def sleep() -> MotionReport:
        """Go to sleep: fold head and antennas down and rest. Say goodbye before, not after."""
        return await backend.sleep()
