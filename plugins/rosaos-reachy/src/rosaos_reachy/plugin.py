"""The ``reachy`` driver: what it declares to rosaOS, and how its backends are built.

Registered under the ``rosaos.drivers`` entry point as ``reachy`` (see ``pyproject.toml``).
The Reachy Mini is rosaOS's user interface: ``always_attached`` grants it to every process, so
any task can speak to the user, and ``shared`` lets them all hold it at once (the driver
serializes motion itself).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from rosaos import hookimpl
from rosaos.card_controls import prompt
from rosaos.cards import Card, flag, head, image, text
from rosaos.drivers import DemoInstance, DeviceContext, DriverSpec, read_packaged_text
from rosaos_reachy.settings import ReachySettings, SimSettings

if TYPE_CHECKING:  # the backend and server import the SDK, OpenCV and NumPy: only where served
    from fastmcp import FastMCP

    from rosaos_reachy.backend import ReachyBackend

Context = DeviceContext[ReachySettings]


def real_backend(ctx: Context) -> ReachyBackend:
    """The ``real`` backend: the daemon of a Reachy Mini Lite or Wireless at ``host``:``daemon_port``."""
    from rosaos_reachy.backend import ReachyBackend

    return ReachyBackend(ctx, ctx.settings, sim=None)


def sim_backend(ctx: Context) -> ReachyBackend:
    """The ``sim`` backend: starts the SDK's daemon in simulation, in the state ``ctx.sim`` gives."""
    from rosaos_reachy.backend import ReachyBackend

    return ReachyBackend(ctx, ctx.settings, sim=SimSettings.from_sim(ctx.instance, dict(ctx.sim)))


def build_server(ctx: Context, backend: ReachyBackend) -> FastMCP:
    """The instance's MCP tools (:mod:`rosaos_reachy.server`), imported where the device is served."""
    from rosaos_reachy.server import build_server as build

    return build(ctx, backend)


async def stop_moving_and_talking(backend: ReachyBackend) -> None:
    """Emergency stop: stop every motion where it is and stop speaking. Motors stay on, holding
    the pose: a head dropping limp would be a motion too."""
    await backend.safe_stop()


SPEECH_WORDS = (
    r"\b(say|said|speak|spoken|tell|told|announce|ask|greet|talk|aloud|voice|read (it |them )?out|"
    r"sing|answer|reply|remind|warn|welcome|thank|introduce|explain|chat|pronounce|call out|"
    r"stop (speaking|talking)|be quiet|silence|shut up)\w*"
)
"""Words of a task that asks the attached Reachy to speak (``DriverSpec.attached_pattern``): a
process the kernel did not give the Reachy by name gets its ``speak`` only with one of them."""

SPEC: DriverSpec[ReachyBackend, ReachySettings] = DriverSpec(
    name="reachy",
    title="Pollen Robotics Reachy Mini",
    description=(
        "The Reachy Mini desktop robot, the user's companion and rosaOS's voice: speak to the user, "
        "turn its head and body, move its antennas, show emotions and dance, wake up and sleep, take "
        "pictures, find, remember and look at faces, and describe what its camera sees."
    ),
    concurrency="shared",
    always_attached=True,  # the user interface: every process can speak to the user
    prompt=read_packaged_text(__file__, "prompt.md"),
    # Granted to a process without being asked (every light switch): speaking only, not the
    # head, camera and emotions, whose schemas were 71 % of a light switch's tools.
    attached_tools=("speak", "stop_speaking"),
    attached_prompt=read_packaged_text(__file__, "attached_prompt.md"),
    # And only to a task that speaks: a process's report reaches the user without it.
    attached_pattern=SPEECH_WORDS,
    settings=ReachySettings,
    server=build_server,
    backends={"sim": sim_backend, "real": real_backend},
    intents=Path(__file__).parent / "intents.yaml",
    safe_stop=stop_moving_and_talking,
    halts=("motion", "speech"),
    card=Card.of(
        head(),
        flag("speaking", label="Speaking"),
        text("moving", label="Moving"),
        text("companion", label="Companion"),
        image(),
        text("mode", label="Mode"),
        controls=[prompt("Say", tool="speak", argument="text", placeholder="Hello, I am Reachy!")],
        noun="desk robot",
    ),
    # Served in the shared host with the other simulators (no own_process): the heavy, native
    # part, the SDK's MuJoCo daemon, is already a child process of its own (daemon.py), and the
    # blocking SDK calls run in threads, so an interpreter of its own only cost ~120 MiB PSS.
    background_start=True,  # the simulator boots for seconds; it joins the shared host later
    demo={
        "reachy": DemoInstance(
            description="Reachy Mini desktop robot, the user's companion on the desk",
            sim={"awake": True, "last_spoken": ""},
        )
    },
)


@hookimpl
def register_drivers(register: Callable[[DriverSpec], None]) -> None:
    """Register the ``reachy`` driver."""
    register(SPEC)
