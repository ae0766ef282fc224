"""The companion's tools: the voice front end says when the robot listens; anyone turns face following on or off.

The companion itself (breathing, listening, swaying, facing people) is :mod:`rosaos_reachy.companion`.
"""

from __future__ import annotations

from typing import Annotated

from fastmcp import FastMCP
from pydantic import Field

from rosaos_reachy.annotations import SET
from rosaos_reachy.backend import ReachyBackend
from rosaos_reachy.state import CompanionReport
from rosaos_reachy.tools.motion import Yaw

ListenSeconds = Annotated[
    float,
    Field(gt=0, le=120, description="Listen at most this long, unless called again with on=false before."),
]


Listening = Annotated[
    bool, Field(description="true when someone starts talking to the robot, false once heard.")
]
Following = Annotated[bool, Field(description="true: keep facing the person in view; false: stop.")]


def register(mcp: FastMCP, backend: ReachyBackend) -> None:
    """Add the tools that steer the companion (the robot's own motion between tasks) to ``mcp``."""

    def report() -> CompanionReport:
        companion = backend.companion
        return CompanionReport(
            companion=companion.mode, follow_face=companion.follow_face, listening=companion.listening
        )

    @mcp.tool(annotations=SET)
    async def set_listening(
        on: Listening, direction: Yaw = None, seconds: ListenSeconds = 10.0
    ) -> CompanionReport:
        """Tell the robot someone is talking to it: the antennas wave while it listens, and it turns
        its head to ``direction`` (degrees, + left, where the voice came from) if given.

        The voice front end calls it on the wake word (on=true) and once the command is heard
        (on=false). A sleeping robot wakes up first (not after an emergency stop, nor with the
        companion off); otherwise it never interrupts a motion a process asked for.
        """
        companion = backend.companion
        if on and not backend.awake and companion.enabled and not companion.stopped:
            await backend.wake_up()
        companion.listen(seconds if on else 0.0, direction)
        return report()

    @mcp.tool(annotations=SET)
    async def follow_face(on: Following) -> CompanionReport:
        """Keep facing the person in view while listening and speaking (on), or stop (off)."""
        backend.companion.follow_face = on
        return report()
