"""ROS 2 messages as rosbridge carries them (JSON dicts), shared by the driver and the simulator.

rosbridge encodes a ROS message as a JSON object whose keys are the field names; ``uint8[]``
fields (image data) travel as base64 strings; times are ``{"sec": int, "nanosec": int}``.
"""

from __future__ import annotations

import math
import re
import time
from collections.abc import Mapping
from typing import Any

TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
IMAGE = "sensor_msgs/msg/Image"
COMPRESSED_IMAGE = "sensor_msgs/msg/CompressedImage"

SUMMARY_STRING_LIMIT = 200
"""Longer strings (base64 image data, blobs) are summarised, so a model never reads raw bytes."""
SUMMARY_LIST_LIMIT = 32
"""Longer arrays (laser ranges, point data) keep their first items and say how many there were."""
_BASE64 = re.compile(r"^[A-Za-z0-9+/]+={0,2}$")


def normalize_type(type_name: str) -> str:
    """``geometry_msgs/Twist`` → ``geometry_msgs/msg/Twist``: ROS 2's full form, for comparisons.

    Service and action types keep their ``srv``/``action`` part.
    """
    parts = type_name.strip().strip("/").split("/")
    if len(parts) == 2:
        return f"{parts[0]}/msg/{parts[1]}"
    return "/".join(parts)


def stamp(now: float | None = None) -> dict[str, int]:
    """A ``builtin_interfaces/Time`` for ``now`` (wall clock seconds; default: the current time)."""
    now = time.time() if now is None else now
    sec = int(now)
    return {"sec": sec, "nanosec": int((now - sec) * 1e9)}


def header(frame_id: str, now: float | None = None) -> dict[str, Any]:
    """A ``std_msgs/Header``."""
    return {"stamp": stamp(now), "frame_id": frame_id}


def quaternion_from_yaw(yaw: float) -> dict[str, float]:
    """A ``geometry_msgs/Quaternion`` for a rotation of ``yaw`` radians about z."""
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}


def yaw_from_quaternion(q: Mapping[str, Any]) -> float:
    """The yaw (rotation about z, radians in (-pi, pi]) of a ``geometry_msgs/Quaternion``."""
    x, y, z, w = (float(q.get(key, 0.0)) for key in ("x", "y", "z", "w"))
    return wrap_angle(math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z)))


def wrap_angle(angle: float) -> float:
    """``angle`` in radians, brought into (-pi, pi] (REP-103: positive is counter-clockwise)."""
    wrapped = math.atan2(math.sin(angle), math.cos(angle))
    return math.pi if wrapped == -math.pi else wrapped


def twist(
    linear: float, angular: float, msg_type: str = TWIST, frame_id: str = "base_link"
) -> dict[str, Any]:
    """A velocity command of ``msg_type`` (Twist or TwistStamped): forward m/s, yaw rate rad/s."""
    body = {
        "linear": {"x": float(linear), "y": 0.0, "z": 0.0},
        "angular": {"x": 0.0, "y": 0.0, "z": float(angular)},
    }
    if normalize_type(msg_type) == TWIST_STAMPED:
        return {"header": header(frame_id), "twist": body}
    return body


def twist_command(msg: Mapping[str, Any]) -> tuple[float, float]:
    """``(linear.x, angular.z)`` of a Twist or TwistStamped: what a differential drive obeys."""
    body = msg["twist"] if isinstance(msg.get("twist"), Mapping) else msg
    linear = body.get("linear") or {}
    angular = body.get("angular") or {}
    return float(linear.get("x", 0.0) or 0.0), float(angular.get("z", 0.0) or 0.0)


def twist_speeds(msg: Mapping[str, Any]) -> tuple[float, float]:
    """``(linear speed, angular speed)`` of a Twist or TwistStamped: the norms of its two vectors.

    Norms, so a sideways, vertical or rolling command is bounded like a forward one or a turn.
    """
    body = msg["twist"] if isinstance(msg.get("twist"), Mapping) else msg

    def norm(vector: Any) -> float:
        if not isinstance(vector, Mapping):
            return 0.0
        return math.sqrt(sum(float(vector.get(axis, 0.0) or 0.0) ** 2 for axis in ("x", "y", "z")))

    return norm(body.get("linear")), norm(body.get("angular"))


def summarize(value: Any, depth: int = 0) -> Any:
    """A copy of a message fit for a model's context: long strings and arrays are summarised.

    Image data (base64) becomes ``"<N bytes of binary data>"``, long text is cut; arrays keep their first
    :data:`SUMMARY_LIST_LIMIT` items followed by ``"... (M items in all)"``.
    """
    if isinstance(value, Mapping):
        return {key: summarize(item, depth + 1) for key, item in value.items()}
    if isinstance(value, list):
        head = [summarize(item, depth + 1) for item in value[:SUMMARY_LIST_LIMIT]]
        if len(value) > SUMMARY_LIST_LIMIT:
            head.append(f"... ({len(value)} items in all)")
        return head
    if isinstance(value, str) and len(value) > SUMMARY_STRING_LIMIT:
        if _BASE64.match(value):
            return f"<{len(value) * 3 // 4} bytes of binary data>"
        return f"{value[:SUMMARY_STRING_LIMIT]}... ({len(value)} characters in all)"
    return value
