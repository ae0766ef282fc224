"""The driver as rosaOS sees it: entry point, spec, settings, demo instances, backends, prompt."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from rosaos.drivers import DeviceError
from rosaos.plugins import load_drivers
from rosaos.processes.jobs import GrantedDevice
from rosaos.processes.tool_offer import offered_names
from rosaos_ros.plugin import SPEC, real_backend, sim_backend
from rosaos_ros.settings import RosSettings

from .conftest import context  # the context the hosting layer builds, as every test here uses


def test_entry_point_registers_the_ros_driver() -> None:
    registry = load_drivers(allow={"ros"})
    assert registry.broken == []
    info = registry.get("ros")
    assert (info.package, info.spec.name, info.spec.implemented) == ("rosaos-ros", "ros", True)


def test_a_robot_is_held_by_one_process_at_a_time() -> None:
    assert SPEC.concurrency == "exclusive"


def test_the_demo_world_has_a_docked_turtlebot_and_a_dog() -> None:
    demo = SPEC.demo_instances()
    assert demo["turtlebot"].settings == {"profile": "turtlebot4"}
    assert demo["turtlebot"].sim["docked"] is True
    assert demo["dog"].settings == {"profile": "puppypi"}


def test_settings_reject_unknown_keys_and_never_show_the_token() -> None:
    with pytest.raises(ValidationError, match="hots"):
        RosSettings.model_validate({"hots": "10.0.0.5"})
    settings = RosSettings(rosbridge_token="hunter2")
    assert "hunter2" not in repr(settings) and "hunter2" not in settings.model_dump_json()


def test_the_sim_table_can_name_the_profile(tmp_path: Path) -> None:
    backend = sim_backend(context(tmp_path, sim={"profile": "puppypi"}))
    try:
        assert backend.profile.name == "puppypi" and backend.simulated
    finally:
        backend.deadman.close()


def test_a_profile_in_settings_and_a_different_one_in_sim_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(DeviceError, match="keep one"):
        sim_backend(context(tmp_path, sim={"profile": "puppypi"}, profile="turtlebot4"))


def test_a_bad_sim_key_names_the_allowed_ones(tmp_path: Path) -> None:
    with pytest.raises(DeviceError, match=r"allowed keys: profile, x, y, yaw"):
        sim_backend(context(tmp_path, sim={"heading": 1}))


def test_a_user_profile_in_the_data_dir_is_found_by_name(tmp_path: Path) -> None:
    profiles = tmp_path / "drivers" / "ros" / "profiles"
    profiles.mkdir(parents=True)
    (profiles / "rover.yaml").write_text(
        "title: Rover\ndescription: A rover.\ncmd_vel: {topic: /cmd_vel, type: geometry_msgs/msg/Twist}\n"
        "limits: {linear: 1.0, angular: 2.0}\nspeeds: {linear: 0.5, angular: 1.0}\n",
        encoding="utf-8",
    )
    backend = real_backend(context(tmp_path, profile="rover", namespace="r1"))
    try:
        assert (backend.profile.name, backend.profile.cmd_vel.topic, backend.simulated) == (
            "rover",
            "/r1/cmd_vel",
            False,
        )
    finally:
        backend.deadman.close()


async def test_every_tool_sets_all_three_hints(open_robot: Any) -> None:
    async with open_robot() as robot:
        tools = await robot.client.list_tools()
    for tool in tools:
        hints = tool.annotations
        assert hints is not None and None not in (
            hints.read_only_hint,
            hints.destructive_hint,
            hints.idempotent_hint,
        ), tool.name


async def test_set_param_is_destructive_so_a_destructive_rule_asks_first(open_robot: Any) -> None:
    async with open_robot() as robot:
        hints = {tool.name: tool.annotations for tool in await robot.client.list_tools()}
    assert hints["set_param"] is not None and hints["set_param"].destructive_hint is True


async def test_the_on_request_tools_are_the_servers_and_a_search_task_is_not_offered_them(
    open_robot: Any,
) -> None:
    # Issue 22: the ROS graph's 25 tools are 13 KB of schema on every request of a drive or search.
    async with open_robot() as robot:
        names = {tool.name for tool in await robot.client.list_tools()}
    assert set(SPEC.on_request_tools) <= names
    device = GrantedDevice(
        name="turtlebot",
        driver="ros",
        url="http://127.0.0.1:1/mcp",
        token="t",
        description="d",
        prompt=SPEC.prompt,
        on_request_tools=list(SPEC.on_request_tools),
        on_request_pattern=SPEC.on_request_pattern,
    )
    search = "Undock, then search the environment for a person and report whether you found one."
    assert offered_names(device, search)[1] == frozenset(SPEC.on_request_tools) | {"safe_stop"}
    assert {"undock", "search", "drive", "stop"} <= names - offered_names(device, search)[1]
    assert offered_names(device, "publish 0.1 on /cmd_vel")[1] == {"safe_stop"}
