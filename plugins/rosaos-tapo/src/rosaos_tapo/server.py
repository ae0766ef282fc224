"""The MCP tools of one Tapo bulb: what a process agent holding the device can call.

Every tool returns the bulb's state read back after acting, so the model sees what happened.
Anything that sets light output (brightness, colour, colour temperature) also turns the bulb on:
"set the lamp to 20 percent" means a lit lamp at 20 percent.
"""

from __future__ import annotations

from typing import Annotated

from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from pydantic import Field

from rosaos import drivers
from rosaos.drivers import DeviceContext
from rosaos_tapo.backend import BulbState, TapoBackend
from rosaos_tapo.colors import UnknownColorError, White, lookup_color

# Annotations, per MCP: every tool only changes a light (never destructive), and setting a
# value twice is the same as once, except for relative changes (toggle, adjust_brightness).
READ_ONLY, SET, CHANGE = drivers.READ_ONLY, drivers.SETS, drivers.CHANGES

Brightness = Annotated[int, Field(ge=0, le=100, description="Percent; 0 turns the light off.")]
BrightnessChange = Annotated[
    int,
    Field(ge=-100, le=100, description="Percentage points; negative dims. The result stays 1-100."),
]
Kelvin = Annotated[int, Field(ge=2500, le=6500, description="2700 warm white, 4000 neutral, 6500 daylight.")]
KelvinChange = Annotated[int, Field(ge=-4000, le=4000, description="Kelvin; negative is warmer.")]
Hue = Annotated[
    int,
    Field(
        ge=0,
        le=360,
        description="Degrees: 0 red, 30 orange, 60 yellow, 120 green, 180 cyan, 240 blue, 300 magenta.",
    ),
]
Saturation = Annotated[int, Field(ge=0, le=100, description="Percent: 0 white, 100 vivid.")]
OptionalBrightness = Annotated[int | None, Field(ge=1, le=100, description="Percent; omit to keep it.")]
ColorName = Annotated[str, Field(min_length=1, max_length=40, description="e.g. red, warm white.")]


def build_server(ctx: DeviceContext, backend: TapoBackend) -> FastMCP:
    """Build the FastMCP server for one bulb instance on a started backend."""
    mcp = FastMCP(name=ctx.instance, instructions=f"{ctx.description} (TP-Link Tapo smart bulb).")

    @mcp.tool(annotations=READ_ONLY)
    async def get_state() -> BulbState:
        """Read the light: on, brightness %, hue, saturation %, color_temp K (0 while in colour)."""
        return await backend.state()

    @mcp.tool(annotations=SET)
    async def turn_on() -> BulbState:
        """Turn the light on, as it was before."""
        return await backend.turn_on()

    @mcp.tool(annotations=SET)
    async def turn_off() -> BulbState:
        """Turn the light off (brightness and colour are kept)."""
        return await backend.turn_off()

    @mcp.tool(annotations=CHANGE)
    async def toggle() -> BulbState:
        """Turn the light off if on, on if off."""
        return await backend.toggle()

    @mcp.tool(annotations=SET)
    async def set_brightness(brightness: Brightness) -> BulbState:
        """Set the brightness and turn the light on; 0 turns it off."""
        return await backend.set_brightness(brightness)

    @mcp.tool(annotations=CHANGE)
    async def adjust_brightness(change: BrightnessChange) -> BulbState:
        """Make the light brighter or dimmer by some points ("dim": -25), and turn it on."""
        return await backend.adjust_brightness(change)

    @mcp.tool(annotations=SET)
    async def set_color_temp(kelvin: Kelvin) -> BulbState:
        """White light at a colour temperature; turns the light on."""
        return await backend.set_color_temp(kelvin)

    @mcp.tool(annotations=CHANGE)
    async def adjust_color_temp(change: KelvinChange) -> BulbState:
        """Make white light warmer or cooler (from a colour: from 4000 K), and turn it on."""
        return await backend.adjust_color_temp(change)

    @mcp.tool(annotations=SET)
    async def set_color(hue: Hue, saturation: Saturation, brightness: OptionalBrightness = None) -> BulbState:
        """Show a colour by hue and saturation, and turn the light on (white: set_color_temp)."""
        return await backend.set_color(hue, saturation, brightness)

    @mcp.tool(annotations=SET)
    async def set_color_name(name: ColorName) -> BulbState:
        """Set a named colour or white, and turn the light on.

        Colours: red, orange, amber, yellow, lime, green, teal, cyan, sky blue, blue, indigo,
        purple, violet, magenta, pink, turquoise, aqua, navy, navy blue, royal blue,
        lavender, lilac, fuchsia, hot pink, crimson, scarlet, coral, gold, mint, emerald.
        Whites: white, warm white, soft white, candlelight, cool white, daylight.
        """
        try:
            color = lookup_color(name)
        except UnknownColorError as error:
            raise ToolError(str(error)) from None
        if isinstance(color, White):
            return await backend.set_color_temp(color.kelvin)
        return await backend.set_color(color.hue, color.saturation)

    return mcp
