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

Brightness = Annotated[
    int, Field(ge=0, le=100, description="Brightness in percent, 1-100; 0 turns the light off.")
]
BrightnessChange = Annotated[
    int,
    Field(ge=-100, le=100, description="Percentage points to add; negative dims. The result stays 1-100."),
]
Kelvin = Annotated[
    int, Field(ge=2500, le=6500, description="White colour temperature in kelvin: 2700 warm, 6500 cool.")
]
KelvinChange = Annotated[
    int, Field(ge=-4000, le=4000, description="Kelvin to add; negative is warmer, positive cooler.")
]
Hue = Annotated[
    int,
    Field(ge=0, le=360, description="Hue in degrees: 0 red, 60 yellow, 120 green, 240 blue, 300 magenta."),
]
Saturation = Annotated[int, Field(ge=0, le=100, description="Saturation in percent: 0 white, 100 vivid.")]
OptionalBrightness = Annotated[
    int | None, Field(ge=1, le=100, description="Brightness in percent, 1-100; omit to keep the current one.")
]
ColorName = Annotated[
    str, Field(min_length=1, max_length=40, description="A colour name, e.g. red, green, warm white.")
]


def build_server(ctx: DeviceContext, backend: TapoBackend) -> FastMCP:
    """Build the FastMCP server for one bulb instance on a started backend."""
    mcp = FastMCP(name=ctx.instance, instructions=f"{ctx.description} (TP-Link Tapo smart bulb).")

    @mcp.tool(annotations=READ_ONLY)
    async def get_state() -> BulbState:
        """Read the light: on/off, brightness %, hue, saturation %, colour temperature in K.

        ``color_temp`` is 0 while the bulb shows a colour; hue and saturation then describe it.
        """
        return await backend.state()

    @mcp.tool(annotations=SET)
    async def turn_on() -> BulbState:
        """Turn the light on, at the brightness and colour it had before."""
        return await backend.turn_on()

    @mcp.tool(annotations=SET)
    async def turn_off() -> BulbState:
        """Turn the light off. Brightness and colour are kept for the next turn_on."""
        return await backend.turn_off()

    @mcp.tool(annotations=CHANGE)
    async def toggle() -> BulbState:
        """Turn the light off if it is on, or on if it is off."""
        return await backend.toggle()

    @mcp.tool(annotations=SET)
    async def set_brightness(brightness: Brightness) -> BulbState:
        """Set the brightness in percent (1-100) and turn the light on; 0 turns it off.

        Colour and colour temperature stay as they are.
        """
        return await backend.set_brightness(brightness)

    @mcp.tool(annotations=CHANGE)
    async def adjust_brightness(change: BrightnessChange) -> BulbState:
        """Make the light brighter or dimmer by some percentage points, and turn it on.

        Use for "dim" (e.g. -25) or "brighter" (e.g. +25) when no exact level is asked for.
        The result is kept within 1-100; to switch the light off use turn_off.
        """
        return await backend.adjust_brightness(change)

    @mcp.tool(annotations=SET)
    async def set_color_temp(kelvin: Kelvin) -> BulbState:
        """Switch to white light at a colour temperature (2500-6500 K) and turn the light on.

        2700 K is warm white (like a classic bulb), 4000 K neutral, 6500 K cool daylight.
        Brightness stays as it is.
        """
        return await backend.set_color_temp(kelvin)

    @mcp.tool(annotations=CHANGE)
    async def adjust_color_temp(change: KelvinChange) -> BulbState:
        """Make white light warmer (negative kelvin) or cooler (positive), and turn the light on.

        Use for "warmer" (e.g. -700) or "cooler" (e.g. +700) when no exact temperature is asked
        for. From a colour, it starts at neutral white (4000 K); the result stays 2500-6500 K.
        """
        return await backend.adjust_color_temp(change)

    @mcp.tool(annotations=SET)
    async def set_color(hue: Hue, saturation: Saturation, brightness: OptionalBrightness = None) -> BulbState:
        """Show a colour given as hue (0-360°) and saturation (0-100 %), and turn the light on.

        The bulb leaves white mode (``color_temp`` becomes 0). Brightness changes only if given.
        For white light use set_color_temp instead.
        """
        return await backend.set_color(hue, saturation, brightness)

    @mcp.tool(annotations=SET)
    async def set_color_name(name: ColorName) -> BulbState:
        """Set the light to a named colour or white, and turn it on.

        Colours: red, orange, amber, yellow, lime, green, teal, cyan, sky blue, blue, indigo,
        purple, violet, magenta, pink. Whites: white, warm white, soft white, candlelight,
        cool white, daylight. Brightness stays as it is.
        """
        try:
            color = lookup_color(name)
        except UnknownColorError as error:
            raise ToolError(str(error)) from None
        if isinstance(color, White):
            return await backend.set_color_temp(color.kelvin)
        return await backend.set_color(color.hue, color.saturation)

    return mcp
