"""The rules: access lists by glob (deny wins, default deny) and velocity limits, with fix-it messages."""

from __future__ import annotations

import pytest

from rosaos_ros.profiles import load_profile
from rosaos_ros.safety import AccessPolicy, Refused, VelocityLimits
from rosaos_ros.settings import RosSettings

TURTLEBOT = load_profile("turtlebot4")


def policy(**settings: object) -> AccessPolicy:
    return AccessPolicy.build("turtlebot", TURTLEBOT, RosSettings.model_validate(settings))


def test_the_profile_allows_what_the_robot_needs_and_nothing_else() -> None:
    rules = policy()
    rules.check("publish", "/cmd_lightring")
    rules.check("actions", "/dock")
    for kind, name in [
        ("publish", "/cmd_vel"),
        ("services", "/robot_power"),
        ("params", "/motion_control:max_speed"),
    ]:
        with pytest.raises(Refused, match="not in the allow-list"):
            rules.check(kind, name)  # type: ignore[arg-type]


def test_config_allow_globs_extend_the_profile() -> None:
    rules = policy(service_allow=["/e_*"], param_allow=["/oakd:*"])
    rules.check("services", "/e_stop")
    rules.check("params", "/oakd:rgb.i_fps")
    rules.check("publish", "/cmd_audio")  # the profile's own list still holds


def test_deny_wins_over_allow_and_names_its_rule() -> None:
    rules = policy(publish_allow=["/*"], publish_deny=["/cmd_audio"])
    rules.check("publish", "/anything")
    with pytest.raises(
        Refused, match=r"denied by the rule '/cmd_audio' \(\[devices.turtlebot\] publish_deny\)"
    ):
        rules.check("publish", "/cmd_audio")


def test_globs_match_whole_names_case_sensitively() -> None:
    rules = policy(publish_allow=["/cmd_*"])
    with pytest.raises(Refused):
        rules.check("publish", "/CMD_X")
    with pytest.raises(Refused):
        rules.check("publish", "/robot/cmd_x")


def test_parameter_services_are_never_callable_whatever_the_lists_say() -> None:
    rules = policy(service_allow=["*"])
    for service in ["/rosapi/set_param", "/rosapi/delete_param", "/motion_control/set_parameters"]:
        with pytest.raises(Refused, match="never allowed"):
            rules.check("services", service)


def test_velocity_limits_come_from_the_profile_unless_configured() -> None:
    default = VelocityLimits.build("turtlebot", TURTLEBOT, RosSettings())
    configured = VelocityLimits.build("turtlebot", TURTLEBOT, RosSettings(max_linear=0.1))
    assert (default.linear, default.angular, configured.linear) == (0.3, 1.9, 0.1)
    default.check(0.3, -1.9)
    with pytest.raises(Refused, match=r"5 m/s is above the velocity limit of 0.3 m/s \(profile turtlebot4\)"):
        default.check(-5.0, 0.0)
    with pytest.raises(Refused, match=r"raise max_angular in \[devices.turtlebot\]"):
        default.check(0.0, 2.5)
    with pytest.raises(Refused, match=r"\[devices.turtlebot\] max_linear\)"):
        configured.check(0.2, 0.0)
