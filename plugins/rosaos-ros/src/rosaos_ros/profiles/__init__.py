"""Robot profiles: what a robot is, as data. One YAML file per robot model.

A profile gives the driver the velocity topic and its limits, the odometry and camera topics,
how ``get_state`` maps topics to keys, the named actions (``dock``, ``undock``) that become
tools, and the default allow-lists (everything else is denied). Its ``sim:`` part tells the
simulator what to pretend (nodes, parameters, a dock, a battery, cameras).

Built-in profiles ship next to this file (``turtlebot4``, ``puppypi``, ``generic``). A user adds
one without code: a YAML file in ``<data_dir>/drivers/ros/profiles/<name>.yaml`` (found by
name, and shadowing a built-in of the same name), or any file named by ``profile_file``.
"""

from __future__ import annotations

import keyword
from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

BUILTIN_DIR = Path(__file__).parent
NAMED_ACTION_RESERVED = frozenset(
    {
        "get_state",
        "get_pose",
        "safe_stop",
        "stop",
        "drive",
        "move_distance",
        "rotate",
        "go_to",
        "capture_image",
        "send_goal",
    }
)
"""Tool names a profile's named action may not take (they are the driver's own tools)."""


class ProfileError(ValueError):
    """A profile that cannot be found or used; the message names the file and the fix."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class TopicRef(_Strict):
    """A topic and its message type."""

    topic: str
    type: str


class StateField(TopicRef):
    """A ``get_state`` key read from one field of the latest message on a topic."""

    field: str
    """Dotted path into the message, e.g. ``percentage`` or ``pose.pose.position.x``."""


class NamedAction(_Strict):
    """A ROS action the profile turns into a tool of its own name (``dock`` → ``/dock``)."""

    action: str
    type: str
    description: str
    goal: dict[str, Any] = Field(default_factory=dict)
    timeout: Annotated[float, Field(gt=0, le=3600)] = 60.0
    leaves: dict[str, Any] = Field(default_factory=dict)
    """State keys the action leaves when it succeeds (``undock`` → ``{docked: false}``). The driver
    waits until the state topics show them before it answers, so the next motion is not refused
    on a status message that was already on its way when the action ended."""


class Navigation(_Strict):
    """Navigation to a pose on a map (Nav2): what ``go_to`` sends, and where the robot is on the map."""

    action: str = "/navigate_to_pose"
    type: str = "nav2_msgs/action/NavigateToPose"
    frame: str = "map"
    """The frame goals are given in, and places are stored in."""
    pose: TopicRef = TopicRef(topic="/amcl_pose", type="geometry_msgs/msg/PoseWithCovarianceStamped")
    """The robot's pose on the map, from localization (AMCL publishes it)."""
    map_param: str | None = "/map_server:yaml_filename"
    """A parameter naming the map (``/node:param``): places saved on one map are not used on another."""
    timeout: Annotated[float, Field(gt=0, le=3600)] = 300.0
    """Seconds a goal may take at most."""


class Limits(_Strict):
    """Velocity bounds: the driver refuses commands above them."""

    linear: Annotated[float, Field(gt=0, le=10)]
    """m/s, forward or backward."""
    angular: Annotated[float, Field(gt=0, le=20)]
    """rad/s, either way."""


class AccessLists(_Strict):
    """Glob lists (``fnmatch``) of full ROS names, per kind of operation that changes the robot."""

    publish: list[str] = Field(default_factory=list)
    services: list[str] = Field(default_factory=list)
    params: list[str] = Field(default_factory=list)
    """Parameter names as rosapi writes them: ``/node:param``."""
    actions: list[str] = Field(default_factory=list)


class SimSpec(_Strict):
    """What the simulator pretends for this profile. Ignored by the driver."""

    base_node: str = "/base"
    """The node that subscribes to the velocity topic and publishes odometry and state topics."""
    topics: dict[str, str] = Field(default_factory=dict)
    """Extra topics the base node subscribes to (name → type), e.g. a light ring."""
    cameras: dict[str, Literal["jpeg", "rgb8"]] = Field(default_factory=dict)
    """Synthetic camera topics: ``jpeg`` (CompressedImage) or ``rgb8`` (raw Image)."""
    camera_node: str = "/camera"
    services: list[Literal["e_stop", "reset_pose"]] = Field(default_factory=list)
    """Simulated services, served by the base node as ``/<name>``."""
    battery: bool = False
    """Publish the ``battery`` state topic (sensor_msgs/BatteryState)."""
    dock: bool = False
    """Publish the ``docked`` state topic (DockStatus) and serve the ``dock``/``undock`` actions."""
    hardware_limits: Limits = Limits(linear=1.0, angular=4.0)
    """What the simulated motors can do, whatever the driver allows."""
    params: dict[str, dict[str, Any]] = Field(default_factory=dict)
    """Declared parameters, per node: ``{"/node": {"name": value}}``."""


class Profile(_Strict):
    """One robot model. See the built-in YAML files for documented examples."""

    name: str
    title: str
    description: str
    cmd_vel: TopicRef
    odom: TopicRef | None = None
    """Odometry (nav_msgs/Odometry). Without it, move_distance/rotate run on time, not feedback."""
    camera: TopicRef | None = None
    state: dict[str, StateField] = Field(default_factory=dict)
    limits: Limits
    speeds: Limits
    """Default speeds of move_distance and rotate (must not exceed ``limits``)."""
    max_drive_duration: Annotated[float, Field(gt=0, le=300)] = 10.0
    refuse_motion_while: str | None = None
    """A boolean state key (e.g. ``docked``) during which motion tools refuse."""
    actions: dict[str, NamedAction] = Field(default_factory=dict)
    navigation: Navigation | None = None
    """Nav2 on a map: ``go_to`` sends NavigateToPose. Without it ``go_to`` drives on odometry."""
    allow: AccessLists = AccessLists()
    deny: AccessLists = AccessLists()
    sim: SimSpec = SimSpec()

    @field_validator("actions")
    @classmethod
    def _action_names_are_tool_names(cls, actions: dict[str, NamedAction]) -> dict[str, NamedAction]:
        for name in actions:
            if not name.isidentifier() or keyword.iskeyword(name) or name in NAMED_ACTION_RESERVED:
                raise ValueError(
                    f"named action {name!r} cannot be a tool name; use a lowercase identifier "
                    f"that is none of {', '.join(sorted(NAMED_ACTION_RESERVED))}"
                )
        return actions

    def namespaced(self, namespace: str) -> Profile:
        """This profile with every absolute ROS name (topics, actions, nodes, globs) under ``namespace``."""
        namespace = "/" + namespace.strip("/") if namespace.strip("/") else ""
        if not namespace:
            return self

        def name(value: str) -> str:
            return namespace + value if value.startswith("/") else value

        def ref(topic: TopicRef | None) -> Any:
            return None if topic is None else topic.model_copy(update={"topic": name(topic.topic)})

        def globs(lists: AccessLists) -> AccessLists:
            return AccessLists(
                **{kind: [name(g) for g in getattr(lists, kind)] for kind in AccessLists.model_fields}
            )

        sim = self.sim.model_copy(
            update={
                "base_node": name(self.sim.base_node),
                "camera_node": name(self.sim.camera_node),
                "topics": {name(t): kind for t, kind in self.sim.topics.items()},
                "cameras": {name(t): kind for t, kind in self.sim.cameras.items()},
                "params": {name(node): params for node, params in self.sim.params.items()},
            }
        )
        return self.model_copy(
            update={
                "cmd_vel": ref(self.cmd_vel),
                "odom": ref(self.odom),
                "camera": ref(self.camera),
                "state": {key: ref(value) for key, value in self.state.items()},
                "actions": {
                    key: value.model_copy(update={"action": name(value.action)})
                    for key, value in self.actions.items()
                },
                "navigation": None
                if self.navigation is None
                else self.navigation.model_copy(
                    update={
                        "action": name(self.navigation.action),
                        "pose": ref(self.navigation.pose),
                        "map_param": None
                        if self.navigation.map_param is None
                        else name(self.navigation.map_param),
                    }
                ),
                "allow": globs(self.allow),
                "deny": globs(self.deny),
                "sim": sim,
            }
        )


def builtin_profiles() -> list[str]:
    """Names of the profiles that ship with the driver."""
    return sorted(path.stem for path in BUILTIN_DIR.glob("*.yaml"))


def find_profile_file(name: str, user_dir: Path | None = None) -> Path:
    """The file of profile ``name``: the user's profiles directory first, then the built-ins."""
    candidates = ([user_dir / f"{name}.yaml"] if user_dir is not None else []) + [
        BUILTIN_DIR / f"{name}.yaml"
    ]
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    add = f"add your own as {user_dir / f'{name}.yaml'}, or" if user_dir is not None else ""
    raise ProfileError(
        f"no robot profile {name!r}: built-in profiles are {', '.join(builtin_profiles())}; "
        f'{add} set profile_file = "/path/to/{name}.yaml"'
    )


def load_profile_file(path: Path) -> Profile:
    """Read and validate one profile file; :class:`ProfileError` says which key is wrong."""
    try:
        raw = yaml.safe_load(path.read_text(encoding="utf-8"))
    except OSError as error:
        raise ProfileError(f"{path}: cannot read the profile: {error.strerror}") from None
    except yaml.YAMLError as error:
        raise ProfileError(f"{path}: not valid YAML: {error}") from None
    if not isinstance(raw, dict):
        raise ProfileError(f"{path}: a profile is a YAML mapping (name, cmd_vel, limits, ...)")
    raw.setdefault("name", path.stem)
    try:
        profile = Profile.model_validate(raw)
    except ValidationError as error:
        problems = "; ".join(
            f"{'.'.join(str(part) for part in problem['loc']) or 'profile'}: {problem['msg']}"
            for problem in error.errors()
        )
        raise ProfileError(f"{path}: {problems}") from None
    for kind in ("linear", "angular"):
        if getattr(profile.speeds, kind) > getattr(profile.limits, kind):
            raise ProfileError(f"{path}: speeds.{kind} is above limits.{kind}; lower it")
    for name, action in profile.actions.items():
        unknown = sorted(set(action.leaves) - set(profile.state))
        if unknown:
            raise ProfileError(
                f"{path}: actions.{name}.leaves names {', '.join(unknown)}, which is not a state key; "
                f"state keys: {', '.join(profile.state) or 'none'}"
            )
    return profile


def load_profile(
    name: str | None = None, *, path: Path | None = None, user_dir: Path | None = None
) -> Profile:
    """The profile given by file ``path``, else by ``name`` (user directory, then built-ins)."""
    if path is not None:
        return load_profile_file(path)
    return load_profile_file(find_profile_file(name or "generic", user_dir))
