"""ROS messages as JSON: angles, twists, type names, and summaries fit for a model."""

from __future__ import annotations

import math

import pytest

from rosaos_ros.messages import (
    normalize_type,
    quaternion_from_yaw,
    summarize,
    twist,
    twist_command,
    twist_speeds,
    wrap_angle,
    yaw_from_quaternion,
)


@pytest.mark.parametrize("yaw", [0.0, 0.5, -2.0, math.pi])
def test_yaw_survives_a_quaternion_round_trip(yaw: float) -> None:
    assert yaw_from_quaternion(quaternion_from_yaw(yaw)) == pytest.approx(yaw)


def test_angles_wrap_into_minus_pi_to_pi() -> None:
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert wrap_angle(-math.pi) == math.pi


def test_twist_and_twist_stamped_carry_the_same_command() -> None:
    plain = twist(0.2, -0.5)
    stamped = twist(0.2, -0.5, "geometry_msgs/TwistStamped")
    assert twist_command(plain) == twist_command(stamped) == (0.2, -0.5)
    assert "header" in stamped


def test_twist_speeds_bound_every_direction() -> None:
    assert twist_speeds({"linear": {"x": 0.3, "y": 0.4}, "angular": {"z": -1.0}}) == (pytest.approx(0.5), 1.0)


def test_type_names_are_compared_in_their_ros2_form() -> None:
    assert normalize_type("geometry_msgs/Twist") == "geometry_msgs/msg/Twist"
    assert normalize_type("irobot_create_msgs/action/Dock") == "irobot_create_msgs/action/Dock"


def test_summaries_hide_binary_data_and_cut_long_arrays() -> None:
    summary = summarize(
        {"data": "A" * 400, "ranges": list(range(100)), "frame": "base_link", "note": "word " * 100}
    )
    assert summary["data"] == "<300 bytes of binary data>"
    assert summary["ranges"][:2] == [0, 1] and summary["ranges"][-1] == "... (100 items in all)"
    assert summary["frame"] == "base_link" and summary["note"].endswith("(500 characters in all)")
