"""The MCP server of one Reachy Mini: state, speech, and the motion and vision tools.

The tools are grouped by role: :mod:`rosaos_reachy.tools.motion` (head, body, antennas,
emotions, wake and sleep), :mod:`rosaos_reachy.tools.companion` (listening, face following) and
:mod:`rosaos_reachy.tools.vision` (camera, faces, vision model).
This module builds the server and holds ``get_state`` and ``speak``.
"""

from __future__ import annotations

from typing import Annotated

from fastmcp import FastMCP
from pydantic import Field

from rosaos.drivers import DeviceContext
from rosaos_reachy.annotations import ACT, READ_ONLY, SET
from rosaos_reachy.backend import ReachyBackend
from rosaos_reachy.speech import SpeechReport, StopReport
from rosaos_reachy.state import ReachyState
from rosaos_reachy.tools import companion, motion, vision

SpokenText = Annotated[
    str,
    Field(min_length=1, max_length=1000, description="Plain text in the user's language."),
]

Interrupt = Annotated[
    bool,
    Field(description="Cut off what is being said (and waiting) and say this now."),
]


def build_server(ctx: DeviceContext, backend: ReachyBackend) -> FastMCP:
    """Build the FastMCP server for one Reachy Mini instance on a started backend."""
    mcp = FastMCP(name=ctx.instance, instructions=f"{ctx.description} (Pollen Robotics Reachy Mini).")

    @mcp.tool(annotations=READ_ONLY)
    async def get_state() -> ReachyState:
        """Read the robot: head pose (x, y, z mm; roll, pitch, yaw degrees), antennas [left, right]
        degrees, body_yaw degrees, awake, last_spoken, and whether it is speaking or moving.

        Angles: yaw + is left, pitch + is down, roll + tilts right; the head's yaw is measured
        from the base, so it includes body_yaw.
        """
        return backend.state()

    @mcp.tool(annotations=ACT)
    async def speak(text: SpokenText, interrupt: Interrupt = False) -> SpeechReport:
        """Say ``text`` aloud; returns once speech starts, with its duration, and speaks on while you go on.

        A sentence said during another follows it, unless ``interrupt``.
        """
        return await backend.speaker.say(text, interrupt=interrupt)

    @mcp.tool(annotations=SET)
    async def stop_speaking() -> StopReport:
        """Stop talking at once, dropping any sentences waiting."""
        return await backend.speaker.stop()

    motion.register(mcp, backend)
    companion.register(mcp, backend)
    vision.register(mcp, backend)
    return mcp
