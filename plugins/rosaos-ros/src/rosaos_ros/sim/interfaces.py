"""The ROS interface definitions the simulated robots use, answered as rosapi's ``TypeDef`` lists.

A real rosapi loads the installed ``.msg``/``.srv``/``.action`` classes. The simulator has no ROS
install, so it keeps the definitions of the types its robots speak here, in the ``.msg`` line
format (``type name [default]``, ``type NAME=value`` for a constant), and answers
``/rosapi/message_details`` and friends with the same ``rosapi_msgs/TypeDef`` shape: one typedef
per type, the asked-for type first, then every nested type once.
"""

from __future__ import annotations

from typing import Any

PRIMITIVES = {
    "bool": "False",
    "byte": "0",
    "char": "0",
    "float32": "0.0",
    "float64": "0.0",
    "int8": "0",
    "uint8": "0",
    "int16": "0",
    "uint16": "0",
    "int32": "0",
    "uint32": "0",
    "int64": "0",
    "uint64": "0",
    "string": "",
    "wstring": "",
}
"""Primitive field types and the example (default) value rosapi shows for each."""

MESSAGES: dict[str, str] = {
    "builtin_interfaces/msg/Time": "int32 sec\nuint32 nanosec",
    "builtin_interfaces/msg/Duration": "int32 sec\nuint32 nanosec",
    "std_msgs/msg/Header": "builtin_interfaces/Time stamp\nstring frame_id",
    "std_msgs/msg/String": "string data",
    "std_msgs/msg/Bool": "bool data",
    "std_msgs/msg/Float64": "float64 data",
    "std_msgs/msg/Empty": "",
    "geometry_msgs/msg/Vector3": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/msg/Point": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/msg/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1",
    "geometry_msgs/msg/Pose": "Point position\nQuaternion orientation",
    "geometry_msgs/msg/PoseStamped": "std_msgs/Header header\nPose pose",
    "geometry_msgs/msg/PoseWithCovariance": "Pose pose\nfloat64[36] covariance",
    "geometry_msgs/msg/Twist": "Vector3 linear\nVector3 angular",
    "geometry_msgs/msg/TwistStamped": "std_msgs/Header header\nTwist twist",
    "geometry_msgs/msg/TwistWithCovariance": "Twist twist\nfloat64[36] covariance",
    "nav_msgs/msg/Odometry": (
        "std_msgs/Header header\nstring child_frame_id\n"
        "geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist"
    ),
    "sensor_msgs/msg/Image": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
        "uint8 is_bigendian\nuint32 step\nuint8[] data"
    ),
    "sensor_msgs/msg/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data",
    "sensor_msgs/msg/BatteryState": (
        "uint8 POWER_SUPPLY_STATUS_UNKNOWN=0\nuint8 POWER_SUPPLY_STATUS_CHARGING=1\n"
        "uint8 POWER_SUPPLY_STATUS_DISCHARGING=2\nuint8 POWER_SUPPLY_STATUS_NOT_CHARGING=3\n"
        "uint8 POWER_SUPPLY_STATUS_FULL=4\n"
        "uint8 POWER_SUPPLY_HEALTH_UNKNOWN=0\nuint8 POWER_SUPPLY_HEALTH_GOOD=1\n"
        "uint8 POWER_SUPPLY_HEALTH_OVERHEAT=2\nuint8 POWER_SUPPLY_HEALTH_DEAD=3\n"
        "uint8 POWER_SUPPLY_HEALTH_OVERVOLTAGE=4\nuint8 POWER_SUPPLY_HEALTH_UNSPEC_FAILURE=5\n"
        "uint8 POWER_SUPPLY_HEALTH_COLD=6\nuint8 POWER_SUPPLY_HEALTH_WATCHDOG_TIMER_EXPIRE=7\n"
        "uint8 POWER_SUPPLY_HEALTH_SAFETY_TIMER_EXPIRE=8\n"
        "uint8 POWER_SUPPLY_TECHNOLOGY_UNKNOWN=0\nuint8 POWER_SUPPLY_TECHNOLOGY_NIMH=1\n"
        "uint8 POWER_SUPPLY_TECHNOLOGY_LION=2\nuint8 POWER_SUPPLY_TECHNOLOGY_LIPO=3\n"
        "uint8 POWER_SUPPLY_TECHNOLOGY_LIFE=4\nuint8 POWER_SUPPLY_TECHNOLOGY_NICD=5\n"
        "uint8 POWER_SUPPLY_TECHNOLOGY_LIMN=6\n"
        "std_msgs/Header header\nfloat32 voltage\nfloat32 temperature\nfloat32 current\n"
        "float32 charge\nfloat32 capacity\nfloat32 design_capacity\nfloat32 percentage\n"
        "uint8 power_supply_status\nuint8 power_supply_health\nuint8 power_supply_technology\n"
        "bool present\nfloat32[] cell_voltage\nfloat32[] cell_temperature\nstring location\n"
        "string serial_number"
    ),
    "irobot_create_msgs/msg/DockStatus": "std_msgs/Header header\nbool dock_visible\nbool is_docked",
    "irobot_create_msgs/msg/LedColor": "uint8 red\nuint8 green\nuint8 blue",
    "irobot_create_msgs/msg/LightringLeds": "std_msgs/Header header\nLedColor[6] leds\nbool override_system",
    "irobot_create_msgs/msg/AudioNote": "uint16 frequency\nbuiltin_interfaces/Duration max_runtime",
    "irobot_create_msgs/msg/AudioNoteVector": "std_msgs/Header header\nAudioNote[] notes\nbool append",
    "unique_identifier_msgs/msg/UUID": "uint8[16] uuid",
    "action_msgs/msg/GoalInfo": "unique_identifier_msgs/UUID goal_id\nbuiltin_interfaces/Time stamp",
    "action_msgs/msg/GoalStatus": (
        "int8 STATUS_UNKNOWN=0\nint8 STATUS_ACCEPTED=1\nint8 STATUS_EXECUTING=2\n"
        "int8 STATUS_CANCELING=3\nint8 STATUS_SUCCEEDED=4\nint8 STATUS_CANCELED=5\n"
        "int8 STATUS_ABORTED=6\nGoalInfo goal_info\nint8 status"
    ),
    "action_msgs/msg/GoalStatusArray": "GoalStatus[] status_list",
}
"""Message definitions by full type name; nested types without a package are in the same package."""

SERVICES: dict[str, tuple[str, str]] = {
    "irobot_create_msgs/srv/EStop": ("bool e_stop_on", "bool success\nstring message"),
    "irobot_create_msgs/srv/ResetPose": ("geometry_msgs/Pose pose", ""),
    "std_srvs/srv/Trigger": ("", "bool success\nstring message"),
    "std_srvs/srv/SetBool": ("bool data", "bool success\nstring message"),
}
"""Service definitions: (request, response)."""

ACTIONS: dict[str, tuple[str, str, str]] = {
    "irobot_create_msgs/action/Dock": ("", "bool is_docked", "bool sees_dock"),
    "irobot_create_msgs/action/Undock": ("", "bool is_docked", ""),
}
"""Action definitions: (goal, result, feedback)."""

ACTION_PARTS = ("Goal", "Result", "Feedback")


class UnknownInterface(LookupError):
    """A type the simulator has no definition for (a real rosapi fails the call the same way)."""


def full_name(type_name: str, package: str = "") -> str:
    """``Vector3`` in ``geometry_msgs`` → ``geometry_msgs/msg/Vector3``; ``pkg/Name`` → ``pkg/msg/Name``."""
    parts = type_name.strip("/").split("/")
    if len(parts) == 1:
        return f"{package}/msg/{parts[0]}"
    if len(parts) == 2:
        return f"{parts[0]}/msg/{parts[1]}"
    return "/".join(parts)


def short_name(type_name: str) -> str:
    """``geometry_msgs/msg/Vector3`` → ``geometry_msgs/Vector3``, as rosapi writes nested types."""
    package, _, name = type_name.rpartition("/")
    return f"{package.split('/')[0]}/{name}"


def definition(type_name: str) -> str:
    """The ``.msg`` text of a message type, including a service's ``_Request``/``_Response`` and an
    action's ``_Goal``/``_Result``/``_Feedback`` (rosapi names them so)."""
    name = full_name(type_name)
    if name in MESSAGES:
        return MESSAGES[name]
    base, _, part = name.rpartition("_")
    if base in SERVICES and part in ("Request", "Response"):
        return SERVICES[base][0 if part == "Request" else 1]
    if base in ACTIONS and part in ACTION_PARTS:
        return ACTIONS[base][ACTION_PARTS.index(part)]
    raise UnknownInterface(f"{type_name}: unknown message type (the simulator knows {len(MESSAGES)} types)")


def typedefs(type_name: str) -> list[dict[str, Any]]:
    """The ``rosapi_msgs/TypeDef`` list for ``type_name``: itself first, then each nested type once."""
    found: list[dict[str, Any]] = []
    seen: set[str] = set()
    pending = [full_name(type_name)]
    while pending:
        name = pending.pop(0)
        if name in seen:
            continue
        seen.add(name)
        typedef = _typedef(name)
        found.append(typedef)
        package = name.split("/")[0]
        for field_type in typedef["fieldtypes"]:
            if field_type not in PRIMITIVES:
                pending.append(full_name(field_type, package))
    return found


def _typedef(name: str) -> dict[str, Any]:
    package = name.split("/")[0]
    typedef: dict[str, Any] = {
        "type": short_name(name),
        "fieldnames": [],
        "fieldtypes": [],
        "fieldarraylen": [],
        "examples": [],
        "constnames": [],
        "constvalues": [],
    }
    for line in definition(name).splitlines():
        field_type, _, rest = line.strip().partition(" ")
        if "=" in rest:  # a constant
            const_name, _, value = rest.partition("=")
            typedef["constnames"].append(const_name.strip())
            typedef["constvalues"].append(value.strip())
            continue
        field_name, _, default = rest.strip().partition(" ")
        base, bracket, size = field_type.partition("[")
        array_len = -1 if not bracket else int(size.rstrip("]") or 0)
        if base not in PRIMITIVES:
            base = short_name(full_name(base, package))
        typedef["fieldnames"].append(field_name)
        typedef["fieldtypes"].append(base)
        typedef["fieldarraylen"].append(array_len)
        example = "[]" if array_len >= 0 else PRIMITIVES.get(base, "{}")
        if default and array_len < 0:
            example = str(float(default)) if base.startswith("float") else default
        typedef["examples"].append(example)
    return typedef
