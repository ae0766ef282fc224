"""Services, parameters and nodes over the socket, with their allow-lists."""

from __future__ import annotations

from typing import Any


async def test_list_services_and_service_info(open_robot: Any) -> None:
    async with open_robot() as robot:
        services = {s["name"]: s["type"] for s in (await robot.call("list_services"))["services"]}
        info = await robot.call("service_info", service="/e_stop")
    assert services["/e_stop"] == "irobot_create_msgs/srv/EStop"
    assert info == {
        "service": "/e_stop",
        "type": "irobot_create_msgs/srv/EStop",
        "node": "/motion_control",
        "allowed": False,
    }


async def test_a_service_outside_the_allow_list_is_refused(open_robot: Any) -> None:
    async with open_robot() as robot:
        error = await robot.error("call_service", service="/e_stop", request={"e_stop_on": True})
    assert "service_allow" in error and robot.world.e_stop is False


async def test_an_allowed_service_is_called_and_answers(open_robot: Any) -> None:
    async with open_robot(service_allow=["/e_stop"]) as robot:
        result = await robot.call("call_service", service="/e_stop", request={"e_stop_on": True})
        await robot.call("drive", linear=0.2, duration=0.3)
    assert result["response"]["success"] is True and robot.world.e_stop is True
    assert robot.world.x == 0.0  # the e-stopped base did not move


async def test_rosapi_param_services_are_never_callable(open_robot: Any) -> None:
    async with open_robot(service_allow=["/*"]) as robot:
        error = await robot.error(
            "call_service", service="/rosapi/set_param", request={"name": "x", "value": "1"}
        )
    assert "never allowed" in error and "use set_param" in error


async def test_params_are_listed_and_read(open_robot: Any) -> None:
    async with open_robot() as robot:
        names = (await robot.call("list_params", node="/motion_control"))["params"]
        value = await robot.call("get_param", name="/motion_control:max_speed")
    assert "/motion_control:max_speed" in names and all(n.startswith("/motion_control:") for n in names)
    assert value == {"name": "/motion_control:max_speed", "value": 0.306}


async def test_setting_a_param_is_denied_by_default_on_the_turtlebot(open_robot: Any) -> None:
    async with open_robot() as robot:
        error = await robot.error("set_param", name="/motion_control:max_speed", value=1.0)
    assert "changing parameter /motion_control:max_speed is not in the allow-list" in error
    assert "param_allow" in error


async def test_the_puppypi_gait_params_can_be_set_and_read_back(open_robot: Any) -> None:
    async with open_robot(instance="dog", profile="puppypi", sim={}) as robot:
        result = await robot.call("set_param", name="/puppy_control:gait.mode", value="Walk")
        wrong_type = await robot.error("set_param", name="/puppy_control:pose.height", value="tall")
        denied = await robot.error("set_param", name="/usb_cam:framerate", value=30.0)
    assert result == {"name": "/puppy_control:gait.mode", "value": "Walk"}
    assert "is a float, not a str" in wrong_type
    assert "not in the allow-list" in denied


async def test_delete_param_needs_the_allow_list_too(open_robot: Any) -> None:
    async with open_robot(param_allow=["/oakd:*"]) as robot:
        denied = await robot.error("delete_param", name="/motion_control:max_speed")
        deleted = await robot.call("delete_param", name="/oakd:rgb.i_fps")
        gone = await robot.error("get_param", name="/oakd:rgb.i_fps")
    assert "not in the allow-list" in denied
    assert deleted["deleted"] is True and "does not exist" in gone


async def test_nodes_are_listed_and_described(open_robot: Any) -> None:
    async with open_robot() as robot:
        nodes = (await robot.call("list_nodes"))["nodes"]
        info = await robot.call("node_info", node="/motion_control")
        missing = await robot.error("node_info", node="/ghost")
    assert {"/motion_control", "/oakd", "/rosapi", "/rosbridge_websocket"} <= set(nodes)
    assert (
        "/cmd_vel" in info["subscribing"] and "/odom" in info["publishing"] and "/e_stop" in info["services"]
    )
    assert "no node /ghost" in missing
