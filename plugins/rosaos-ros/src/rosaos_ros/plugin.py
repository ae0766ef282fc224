"""The ``ros`` driver: what it declares to rosaOS, and how its backends are built.

Registered under the ``rosaos.drivers`` entry point as ``ros`` (see ``pyproject.toml``).
"""

from __future__ import annotations

import secrets
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pydantic import SecretStr

from rosaos import hookimpl
from rosaos.card_controls import button
from rosaos.cards import Card, flag, gauge, image, pose
from rosaos.drivers import DemoInstance, DeviceContext, DeviceError, DriverSpec, read_packaged_text
from rosaos_ros.notices import NOTICES
from rosaos_ros.profiles import Profile, ProfileError, load_profile
from rosaos_ros.settings import RosSettings

if TYPE_CHECKING:  # the backend, its tools and the simulator load only where the device is served
    from fastmcp import FastMCP

    from rosaos_ros.backend import RosBackend

Context = DeviceContext[RosSettings]


def profiles_dir(ctx: DeviceContext[Any]) -> Path:
    """Where a user's own profiles are found by name: ``<data_dir>/drivers/ros/profiles``."""
    return ctx.data_dir / "drivers" / "ros" / "profiles"


def _profile(ctx: Context, settings: RosSettings, sim_profile: str | None = None) -> Profile:
    where = f"[devices.{ctx.instance}]"
    if settings.profile and sim_profile and settings.profile != sim_profile:
        raise DeviceError(
            f"{where} says profile = {settings.profile!r} but its sim table says profile = {sim_profile!r}; keep one"
        )
    try:
        profile = load_profile(
            settings.profile or sim_profile or "generic",
            path=settings.profile_file,
            user_dir=profiles_dir(ctx),
        )
    except ProfileError as error:
        raise DeviceError(f"{where} profile: {error}") from None
    return profile.namespaced(settings.namespace)


def real_backend(ctx: Context) -> RosBackend:
    """The ``real`` backend: a robot running rosbridge at ``host:rosbridge_port``."""
    from rosaos_ros.backend import RosBackend

    settings = ctx.settings
    return RosBackend(ctx.instance, settings, _profile(ctx, settings), ctx.images_dir, notify=ctx.notify)


def sim_backend(ctx: Context) -> RosBackend:
    """The ``sim`` backend: the rosbridge simulator in a thread on a free loopback port, reached over its socket.

    ``ctx.sim`` is the simulator's initial state (``x``, ``y``, ``yaw``, ``docked``, ``battery``,
    ``dock``) and may name the ``profile``; ``host`` and ``rosbridge_port`` are not used.
    """
    from rosaos_ros.backend import RosBackend
    from rosaos_ros.sim import Simulator, SimulatorError, SimulatorThread, sim_state

    settings = ctx.settings
    try:
        state = sim_state(ctx.sim)
    except SimulatorError as error:
        raise DeviceError(f"[devices.{ctx.instance}] {error}") from None
    profile = _profile(ctx, settings, state.profile)
    # The simulator's port is on loopback, where any local process could publish /cmd_vel past the
    # leases and the latch: it always wants a token, a fresh one unless one is configured.
    if settings.rosbridge_token is None:
        settings = settings.model_copy(update={"rosbridge_token": SecretStr(secrets.token_urlsafe(24))})
    assert settings.rosbridge_token is not None
    token = settings.rosbridge_token.get_secret_value()
    simulator = Simulator(profile, state, host="127.0.0.1", port=0, token=token)
    return RosBackend(
        ctx.instance,
        settings,
        profile,
        ctx.images_dir,
        simulator=SimulatorThread(simulator),
        notify=ctx.notify,
    )


def build_server(ctx: Context, backend: RosBackend) -> FastMCP:
    """The robot's MCP tools (:mod:`rosaos_ros.server`), imported where the device is served."""
    from rosaos_ros.server import build_server as build

    return build(ctx, backend)


async def stop_robot(backend: RosBackend) -> None:
    """Emergency stop: zero velocity, end the running motion, cancel every running action goal."""
    await backend.safe_stop()


ROS_GRAPH_TOOLS = (
    "list_topics",
    "topic_info",
    "subscribe_once",
    "subscribe_for",
    "publish",
    "publish_for",
    "list_services",
    "service_info",
    "call_service",
    "list_params",
    "get_param",
    "set_param",
    "delete_param",
    "has_param",
    "param_details",
    "list_nodes",
    "node_info",
    "list_actions",
    "send_goal",
    "cancel_goal",
    "goal_status",
    "action_status",
    "message_details",
    "service_details",
    "action_details",
)
"""The tools on ROS's own terms (topics, services, parameters, actions, nodes, interfaces)."""
ROS_GRAPH_WORDS = (
    r"\b(topics?|services?|param(eter)?s?|actions?|nodes?|messages?|msgs?|publish\w*|subscrib\w*|"
    r"goals?|interfaces?|ros ?2?|rosbridge)\b|(^|[\s'\"(`])/[a-z_]"
)
"""Words of a task that asks for :data:`ROS_GRAPH_TOOLS`, or an absolute ROS name such as ``/cmd_vel``."""

SPEC: DriverSpec[RosBackend, RosSettings] = DriverSpec(
    name="ros",
    title="ROS 2 robot (via rosbridge)",
    description=(
        "A ROS 2 robot reached through rosbridge (TurtleBot 4, PuppyPi, or any base with a velocity topic): "
        "drive it, move a distance or turn an angle on odometry, stop, dock and undock, take a picture, "
        "read its pose, battery and docking state, and use its topics, services, actions, parameters and "
        "nodes within allow-lists and velocity limits."
    ),
    concurrency="exclusive",
    prompt=read_packaged_text(__file__, "prompt.md"),
    # The ROS graph itself: offered to a process model only when its task speaks of it
    # ("publish 0.2 on /cmd_vel", "what does /battery_state say?"), not for a drive or a search.
    on_request_tools=ROS_GRAPH_TOOLS,
    on_request_pattern=ROS_GRAPH_WORDS,
    settings=RosSettings,
    server=build_server,
    backends={"sim": sim_backend, "real": real_backend},
    intents=Path(__file__).parent / "intents.yaml",
    safe_stop=stop_robot,
    halts=("motion",),
    notices=NOTICES,
    card=Card.of(
        pose(),
        flag("docked", label="Dock", on_text="docked", off_text="undocked"),
        gauge("battery", label="Battery", unit="%", max=1.0),
        image(),
        controls=[
            button("Stop", "stop", preempts=True),  # stops the task driving the robot, then the robot
            # Only a robot with a dock has ``docked`` in its state (a TurtleBot 4, not a PuppyPi).
            button("Dock", "dock", shown_when={"docked": False}),
            button("Undock", "undock", shown_when={"docked": True}),
        ],
        noun="robot",
    ),
    confirm_on_real=True,  # a real robot moves only after a person's yes, unless config says otherwise
    demo={
        "turtlebot": DemoInstance(
            description="TurtleBot 4 wheeled mobile robot with a camera and a charging dock",
            settings={"profile": "turtlebot4"},
            sim={"x": 0.0, "y": 0.0, "yaw": 0.0, "docked": True},
            aliases=["turtle bot", "turtlebot 4"],
        ),
        "dog": DemoInstance(
            description="Hiwonder PuppyPi quadruped robot dog",
            settings={"profile": "puppypi"},
            sim={"x": 0.0, "y": 0.0, "yaw": 0.0},
            aliases=["puppypi", "puppy", "robot dog"],
        ),
    },
)


@hookimpl
def register_drivers(register: Callable[[DriverSpec], None]) -> None:
    """Register the ``ros`` driver."""
    register(SPEC)
