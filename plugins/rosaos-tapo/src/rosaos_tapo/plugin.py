"""The ``tapo`` driver: what it declares to rosaOS, and how its backends are built.

Registered under the ``rosaos.drivers`` entry point as ``tapo`` (see ``pyproject.toml``).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from pydantic import BaseModel, Field

from rosaos import hookimpl
from rosaos.card_controls import choice, slider, toggle
from rosaos.cards import Card, swatch
from rosaos.drivers import (
    DemoInstance,
    DeviceContext,
    DeviceError,
    DriverSpec,
    NoticeSpec,
    read_packaged_text,
)
from rosaos_tapo.settings import TapoSettings

if TYPE_CHECKING:  # the backend and the simulator import python-kasa and aiohttp: only where served
    from fastmcp import FastMCP

    from rosaos_tapo.backend import TapoBackend

__all__ = ["SPEC", "TapoSettings", "real_backend", "sim_backend"]

Context = DeviceContext[TapoSettings]


def real_backend(ctx: Context) -> TapoBackend:
    """The ``real`` backend: a bulb on the LAN, reached with the owner's TP-Link account."""
    from rosaos_tapo.backend import TapoBackend

    settings = ctx.settings
    where = f"[devices.{ctx.instance}]"
    if not settings.host:
        raise DeviceError(
            f'{where} needs host = "<bulb IP>" for the real backend (see the Tapo app: Device info)'
        )
    if not settings.username or settings.password is None:
        raise DeviceError(
            f"{where} needs username and password for the real backend: "
            "the email and password of your TP-Link cloud (Tapo app) account"
        )
    backend = TapoBackend.real(
        ctx.instance,
        settings.host,
        settings.username,
        settings.password.get_secret_value(),
        timeout=settings.timeout,
        port=settings.bulb_port,
        connection=settings.connection,
    )
    backend.notify = ctx.notify
    return backend


def sim_backend(ctx: Context) -> TapoBackend:
    """The ``sim`` backend: an in-process L530E that starts in the state ``ctx.sim`` gives."""
    from rosaos_tapo.backend import TapoBackend
    from rosaos_tapo.simulator import SimState

    backend = TapoBackend.simulated_bulb(ctx.instance, SimState.from_sim(ctx.instance, dict(ctx.sim)))
    backend.notify = ctx.notify
    return backend


def build_server(ctx: Context, backend: TapoBackend) -> FastMCP:
    """The bulb's MCP tools (:mod:`rosaos_tapo.server`), imported where the device is served."""
    from rosaos_tapo.server import build_server as build

    return build(ctx, backend)


CARD_COLOURS = [
    "warm white",
    "daylight",
    "red",
    "orange",
    "yellow",
    "green",
    "teal",
    "blue",
    "purple",
    "pink",
]
"""The colours the card offers (``set_color_name`` knows more; the chat can ask for any)."""


class UnreachableData(BaseModel):
    """Why the bulb is taken for gone."""

    error: str = Field(max_length=300)


NOTICES = {
    "unreachable": NoticeSpec(
        description="The bulb stopped answering (unplugged, switched off at the wall, off the network)",
        importance="notify",
        data=UnreachableData,
        example={"error": "cannot reach Tapo bulb at 192.168.1.20"},
    ),
    "reachable": NoticeSpec(description="The bulb answers again after being unreachable"),
}


async def leave_light_as_is(backend: TapoBackend) -> None:
    """Emergency stop for a bulb: do nothing.

    A light cannot hurt anyone, and switching it off in an emergency would leave people in the
    dark while they deal with a robot. So an emergency stop leaves every bulb as it is.
    """


SPEC: DriverSpec[TapoBackend, TapoSettings] = DriverSpec(
    name="tapo",
    title="TP-Link Tapo smart bulb",
    description=(
        "A TP-Link Tapo smart light bulb: turn it on or off or toggle it, set its brightness, "
        "its white colour temperature (warm to cool) or any colour by name or hue, "
        "and read whether it is on and how it is set."
    ),
    concurrency="exclusive",
    prompt=read_packaged_text(__file__, "prompt.md"),
    settings=TapoSettings,
    server=build_server,
    backends={"sim": sim_backend, "real": real_backend},
    intents=Path(__file__).parent / "intents.yaml",
    safe_stop=leave_light_as_is,
    notices=NOTICES,
    # The web page draws the bulb's real colour and brightness, named, with its usual controls.
    card=Card.of(
        swatch(),
        controls=[
            toggle("Power", on_tool="turn_on", off_tool="turn_off", key="on"),
            slider(
                "Brightness", tool="set_brightness", argument="brightness", key="brightness", min=1, unit="%"
            ),
            choice("Colour", tool="set_color_name", argument="name", options=CARD_COLOURS),
        ],
        noun="lamp",
    ),
    demo={
        "kitchen_light": DemoInstance(description="Ceiling light in the kitchen", sim={"on": False}),
        "living_room_lamp": DemoInstance(
            description="Floor lamp in the living room",
            sim={"on": True, "brightness": 60, "color_temp": 2700},
        ),
    },
)


@hookimpl
def register_drivers(register: Callable[[DriverSpec], None]) -> None:
    """Register the ``tapo`` driver."""
    register(SPEC)
