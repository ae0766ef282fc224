"""Robot profiles are data: the built-ins load, namespaces apply, a user adds one without code."""

from __future__ import annotations

from pathlib import Path

import pytest

from rosaos_ros.profiles import ProfileError, builtin_profiles, load_profile


def test_the_built_in_profiles_are_turtlebot4_puppypi_and_generic() -> None:
    assert builtin_profiles() == ["generic", "puppypi", "turtlebot4"]
    for name in builtin_profiles():
        assert load_profile(name).name == name


def test_the_turtlebot4_profile_maps_docking_and_battery_and_names_its_actions() -> None:
    profile = load_profile("turtlebot4")
    assert (profile.state["docked"].field, profile.state["battery"].field) == ("is_docked", "percentage")
    assert profile.actions["dock"].type == "irobot_create_msgs/action/Dock"
    assert (
        profile.allow.actions == ["/dock", "/undock", "/navigate_to_pose"]
        and "/cmd_vel" not in profile.allow.publish
    )


def test_a_namespace_prefixes_every_name_and_glob() -> None:
    profile = load_profile("turtlebot4").namespaced("robot1")
    assert profile.cmd_vel.topic == "/robot1/cmd_vel"
    assert profile.actions["dock"].action == "/robot1/dock"
    assert profile.allow.publish == ["/robot1/cmd_lightring", "/robot1/cmd_audio"]
    assert "/robot1/motion_control" in profile.sim.params


def test_a_user_profile_is_found_by_name_in_the_profiles_directory(tmp_path: Path) -> None:
    (tmp_path / "rover.yaml").write_text(
        "title: Rover\ndescription: A rover.\ncmd_vel: {topic: /rover/cmd_vel, type: geometry_msgs/msg/TwistStamped}\n"
        "limits: {linear: 1.0, angular: 2.0}\nspeeds: {linear: 0.5, angular: 1.0}\n",
        encoding="utf-8",
    )
    profile = load_profile("rover", user_dir=tmp_path)
    assert (profile.name, profile.odom, profile.limits.linear) == ("rover", None, 1.0)


def test_an_unknown_profile_lists_the_built_ins_and_says_where_to_add_one(tmp_path: Path) -> None:
    with pytest.raises(ProfileError, match="built-in profiles are generic, puppypi, turtlebot4") as caught:
        load_profile("spot", user_dir=tmp_path)
    assert str(tmp_path / "spot.yaml") in str(caught.value) and "profile_file" in str(caught.value)


def test_a_bad_profile_names_the_key(tmp_path: Path) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(
        "title: x\ndescription: y\ncmd_vel: {topic: /cmd_vel}\nlimits: {linear: 0}\n", encoding="utf-8"
    )
    with pytest.raises(ProfileError, match=r"cmd_vel\.type: Field required") as caught:
        load_profile(path=path)
    assert "limits.linear" in str(caught.value)


def test_default_speeds_cannot_exceed_the_limits(tmp_path: Path) -> None:
    path = tmp_path / "fast.yaml"
    path.write_text(
        "title: x\ndescription: y\ncmd_vel: {topic: /cmd_vel, type: geometry_msgs/msg/Twist}\n"
        "limits: {linear: 0.2, angular: 1.0}\nspeeds: {linear: 0.5, angular: 0.5}\n",
        encoding="utf-8",
    )
    with pytest.raises(ProfileError, match=r"speeds\.linear is above limits\.linear"):
        load_profile(path=path)


def test_a_named_action_cannot_shadow_a_driver_tool(tmp_path: Path) -> None:
    path = tmp_path / "clash.yaml"
    path.write_text(
        "title: x\ndescription: y\ncmd_vel: {topic: /cmd_vel, type: geometry_msgs/msg/Twist}\n"
        "limits: {linear: 0.2, angular: 1.0}\nspeeds: {linear: 0.1, angular: 0.5}\n"
        "actions: {stop: {action: /halt, type: a/action/B, description: z}}\n",
        encoding="utf-8",
    )
    with pytest.raises(ProfileError, match="'stop' cannot be a tool name"):
        load_profile(path=path)


def test_what_a_named_action_leaves_must_be_a_state_key(tmp_path: Path) -> None:
    path = tmp_path / "leaves.yaml"
    path.write_text(
        "title: x\ndescription: y\ncmd_vel: {topic: /cmd_vel, type: geometry_msgs/msg/Twist}\n"
        "limits: {linear: 0.2, angular: 1.0}\nspeeds: {linear: 0.1, angular: 0.5}\n"
        "actions: {undock: {action: /undock, type: a/action/B, description: z, leaves: {docked: false}}}\n",
        encoding="utf-8",
    )
    with pytest.raises(ProfileError, match="leaves names docked, which is not a state key"):
        load_profile(path=path)


def test_the_turtlebot4_dock_actions_say_what_they_leave() -> None:
    actions = load_profile("turtlebot4").actions
    assert actions["undock"].leaves == {"docked": False}
    assert actions["dock"].leaves == {"docked": True}
