"""Interface schemas, parameter details and action status: what a model needs on an unknown robot."""

from __future__ import annotations

import asyncio
from typing import Any

from rosaos_ros.interfaces import structure
from rosaos_ros.sim.interfaces import typedefs

VECTOR3 = {"type": "geometry_msgs/msg/Vector3", "fields": {"x": "float64", "y": "float64", "z": "float64"}}


async def test_message_details_nests_the_fields_of_twist(open_robot: Any) -> None:
    async with open_robot() as robot:
        twist = await robot.call("message_details", msg_type="geometry_msgs/Twist")
    assert twist["type"] == "geometry_msgs/msg/Twist"
    assert twist["fields"] == {"linear": VECTOR3, "angular": VECTOR3}
    zero = {"x": 0.0, "y": 0.0, "z": 0.0}
    assert twist["example"] == {"linear": zero, "angular": zero}


async def test_message_details_of_a_topic_looks_its_type_up(open_robot: Any) -> None:
    async with open_robot() as robot:
        odom = await robot.call("message_details", msg_type="/odom")
    assert odom["topic"] == "/odom" and odom["type"] == "nav_msgs/msg/Odometry"
    pose = odom["fields"]["pose"]
    assert pose["type"] == "geometry_msgs/msg/PoseWithCovariance"
    assert pose["fields"]["covariance"] == "float64[36]"
    assert pose["fields"]["pose"]["fields"]["orientation"]["fields"]["w"] == "float64"
    assert odom["example"]["pose"]["pose"]["orientation"]["w"] == 1.0
    assert odom["example"]["pose"]["covariance"] == [0.0] * 36
    assert odom["example"]["header"]["stamp"] == {"sec": 0, "nanosec": 0}


async def test_constants_and_arrays_of_messages_are_shown(open_robot: Any) -> None:
    async with open_robot() as robot:
        battery = await robot.call("message_details", msg_type="sensor_msgs/msg/BatteryState")
        lightring = await robot.call("message_details", msg_type="/cmd_lightring")
    assert battery["constants"]["POWER_SUPPLY_STATUS_CHARGING"] == "1"
    assert battery["fields"]["cell_voltage"] == "float32[]"
    leds = lightring["fields"]["leds"]
    assert leds["array"] == 6 and leds["fields"] == {"red": "uint8", "green": "uint8", "blue": "uint8"}
    assert lightring["example"]["leds"] == [{"red": 0, "green": 0, "blue": 0}] * 6


async def test_service_details_give_request_and_response(open_robot: Any) -> None:
    async with open_robot() as robot:
        e_stop = await robot.call("service_details", service_type="/e_stop")
        reset = await robot.call("service_details", service_type="irobot_create_msgs/srv/ResetPose")
    assert e_stop["service"] == "/e_stop" and e_stop["type"] == "irobot_create_msgs/srv/EStop"
    assert e_stop["request"]["fields"] == {"e_stop_on": "bool"}
    assert e_stop["response"]["fields"] == {"success": "bool", "message": "string"}
    assert reset["request"]["fields"]["pose"]["type"] == "geometry_msgs/msg/Pose"
    assert reset["response"]["fields"] == {}


async def test_action_details_give_goal_result_and_feedback(open_robot: Any) -> None:
    async with open_robot() as robot:
        dock = await robot.call("action_details", action_type="/dock")
    assert dock["action"] == "/dock" and dock["type"] == "irobot_create_msgs/action/Dock"
    assert dock["goal"]["fields"] == {} and dock["goal"]["example"] == {}
    assert dock["result"]["fields"] == {"is_docked": "bool"}
    assert dock["feedback"]["fields"] == {"sees_dock": "bool"}


async def test_an_unknown_type_is_a_clear_error(open_robot: Any) -> None:
    async with open_robot() as robot:
        error = await robot.error("message_details", msg_type="made_up_msgs/msg/Nothing")
        no_topic = await robot.error("message_details", msg_type="/no_such_topic")
    assert "does not know the message type made_up_msgs/msg/Nothing" in error
    assert "no topic /no_such_topic" in no_topic


async def test_action_details_fall_back_to_the_generated_messages_on_an_older_rosapi(
    open_robot: Any,
) -> None:
    async with open_robot() as robot:
        assert robot.backend.simulator is not None
        graph = robot.backend.simulator.simulator.graph
        for part in ("goal", "result", "feedback"):
            graph.remove_service(f"/rosapi/action_{part}_details")
        undock = await robot.call("action_details", action_type="irobot_create_msgs/action/Undock")
    assert undock["result"]["fields"] == {"is_docked": "bool"} and undock["feedback"]["fields"] == {}


async def test_has_param_and_param_details(open_robot: Any) -> None:
    async with open_robot(param_allow=["/motion_control:*"]) as robot:
        exists = await robot.call("has_param", name="/motion_control:max_speed")
        missing = await robot.call("has_param", name="/motion_control:no_such")
        details = await robot.call("param_details", name="/motion_control:max_speed")
        error = await robot.error("param_details", name="/motion_control:no_such")
    assert exists == {"name": "/motion_control:max_speed", "exists": True}
    assert missing["exists"] is False
    assert details["node"] == "/motion_control" and details["type"] == "double"
    assert details["settable"] is True and isinstance(details["value"], float)
    assert "no parameter /motion_control:no_such" in error


async def test_action_status_shows_goals_sent_by_another_client(open_robot: Any) -> None:
    async with open_robot(sim={"x": 1.0}) as robot:
        before = await robot.call("action_status", action="/dock", timeout=0.5)
        # a goal that is not ours: the backend's own tracker sends it, action_status never sees its id
        sent = await robot.call("send_goal", action="/dock", goal={}, wait=False)
        await asyncio.sleep(0.3)
        running = await robot.call("action_status", action="/dock")
        await robot.call("cancel_goal", goal_id=sent["goal_id"])
        ended = await robot.call("action_status", action="/dock")
        error = await robot.error("action_status", action="/nowhere")
    assert before["goals"] == [] and before["active"] == 0
    assert running["active"] == 1 and running["goals"][0]["status"] == "executing"
    assert len(running["goals"][0]["goal_id"]) == 32
    assert ended["active"] == 0 and ended["goals"][0]["status"] == "canceled"
    assert "no action server /nowhere" in error


def test_the_simulator_answers_in_rosapi_typedef_shape() -> None:
    twist = typedefs("geometry_msgs/msg/Twist")
    assert [t["type"] for t in twist] == ["geometry_msgs/Twist", "geometry_msgs/Vector3"]
    assert set(twist[0]) == {
        "type",
        "fieldnames",
        "fieldtypes",
        "fieldarraylen",
        "examples",
        "constnames",
        "constvalues",
    }
    assert twist[0]["fieldtypes"] == ["geometry_msgs/Vector3"] * 2 and twist[0]["examples"] == ["{}", "{}"]
    assert structure(twist)["fields"]["linear"] == VECTOR3
