"""The rosbridge v2 protocol of the simulator, spoken by a bare WebSocket client (no roslibpy)."""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import json
import time
from collections.abc import AsyncIterator, Callable
from typing import Any

import pytest
from websockets.asyncio.client import ClientConnection, connect
from websockets.exceptions import InvalidStatus

from rosaos_ros.profiles import load_profile
from rosaos_ros.sim import Simulator
from rosaos_ros.sim.graph import BRIDGE_NODE

TWIST = {"linear": {"x": 0.1, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}


class Peer:
    """A rosbridge client speaking raw JSON."""

    def __init__(self, connection: ClientConnection) -> None:
        self.connection = connection

    async def send(self, **message: Any) -> None:
        await self.connection.send(json.dumps(message))

    async def receive(self, match: Callable[[dict[str, Any]], bool], timeout: float = 3.0) -> dict[str, Any]:
        """The next message ``match`` accepts (others are skipped)."""
        async with asyncio.timeout(timeout):
            while True:
                message = json.loads(await self.connection.recv())
                if match(message):
                    return message

    async def collect(self, op: str, topic: str, seconds: float) -> list[dict[str, Any]]:
        """Every ``op`` message on ``topic`` for ``seconds``."""
        found: list[dict[str, Any]] = []
        deadline = time.monotonic() + seconds
        while (remaining := deadline - time.monotonic()) > 0:
            try:
                message = json.loads(await asyncio.wait_for(self.connection.recv(), remaining))
            except TimeoutError:
                break
            if message.get("op") == op and message.get("topic") == topic:
                found.append(message)
        return found

    async def call(self, service: str, **args: Any) -> dict[str, Any]:
        await self.send(op="call_service", id=f"call:{service}", service=service, args=args)
        return await self.receive(
            lambda m: m.get("op") == "service_response" and m.get("id") == f"call:{service}"
        )


@pytest.fixture
async def sim() -> AsyncIterator[Simulator]:
    simulator = Simulator(load_profile("turtlebot4"), {"x": 0.1})
    await simulator.start()
    yield simulator
    await simulator.stop()


@contextlib.asynccontextmanager
async def peer(sim: Simulator, **kwargs: Any) -> AsyncIterator[Peer]:
    async with connect(sim.url, **kwargs) as connection:
        yield Peer(connection)


async def test_a_publish_reaches_another_clients_subscription(sim: Simulator) -> None:
    async with peer(sim) as talker, peer(sim) as listener:
        await listener.send(op="subscribe", id="sub:1", topic="/chatter", type="std_msgs/msg/String")
        await talker.send(op="advertise", id="adv:1", topic="/chatter", type="std_msgs/msg/String")
        await asyncio.sleep(0.05)
        await talker.send(op="publish", topic="/chatter", msg={"data": "hello"})
        message = await listener.receive(lambda m: m.get("topic") == "/chatter")
    assert message == {"op": "publish", "topic": "/chatter", "msg": {"data": "hello"}}


async def test_cmd_vel_from_a_client_moves_the_simulated_base(sim: Simulator) -> None:
    async with peer(sim) as client:
        for _ in range(10):
            await client.send(op="publish", topic="/cmd_vel", msg=TWIST)
            await asyncio.sleep(0.02)
    assert sim.world.x > 0.1


async def test_throttle_rate_limits_how_often_a_subscriber_hears(sim: Simulator) -> None:
    async with peer(sim) as client:
        await client.send(
            op="subscribe", id="odom", topic="/odom", type="nav_msgs/msg/Odometry", throttle_rate=200
        )
        messages = await client.collect("publish", "/odom", 1.0)
    assert 3 <= len(messages) <= 7  # 50 Hz odometry, at most one per 200 ms


async def test_queue_length_keeps_the_newest_messages_while_throttled(sim: Simulator) -> None:
    async with peer(sim) as client:
        await client.send(op="subscribe", id="odom", topic="/odom", throttle_rate=250, queue_length=1)
        messages = await client.collect("publish", "/odom", 1.0)
    assert 3 <= len(messages) <= 6
    stamps = [
        m["msg"]["header"]["stamp"]["sec"] + m["msg"]["header"]["stamp"]["nanosec"] / 1e9 for m in messages
    ]
    assert all(later - earlier > 0.15 for earlier, later in itertools.pairwise(stamps))


async def test_unsubscribe_stops_the_messages(sim: Simulator) -> None:
    async with peer(sim) as client:
        await client.send(op="subscribe", id="odom", topic="/odom")
        await client.receive(lambda m: m.get("topic") == "/odom")
        await client.send(op="unsubscribe", id="odom", topic="/odom")
        await asyncio.sleep(0.1)
        late = await client.collect("publish", "/odom", 0.3)
    assert late == []


async def test_a_disconnected_clients_subscriptions_are_dropped(sim: Simulator) -> None:
    async with peer(sim) as client:
        await client.send(
            op="subscribe", id="s", topic="/dock_status", type="irobot_create_msgs/msg/DockStatus"
        )
        await client.receive(lambda m: m.get("topic") == "/dock_status")
        assert BRIDGE_NODE in sim.graph.topics["/dock_status"].subscribers
    await asyncio.sleep(0.1)
    assert BRIDGE_NODE not in sim.graph.topics["/dock_status"].subscribers
    assert not sim.graph.has_bridge_subscribers("/dock_status")


async def test_rosapi_answers_introspection(sim: Simulator) -> None:
    async with peer(sim) as client:
        topics = await client.call("/rosapi/topics")
        topic_type = await client.call("/rosapi/topic_type", topic="/odom")
        details = await client.call("/rosapi/node_details", node="/motion_control")
        param = await client.call("/rosapi/get_param", name="/motion_control:max_speed")
    assert "/cmd_vel" in topics["values"]["topics"]
    assert topic_type["values"] == {"type": "nav_msgs/msg/Odometry"}
    assert "/cmd_vel" in details["values"]["subscribing"] and "/odom" in details["values"]["publishing"]
    assert json.loads(param["values"]["value"]) == 0.306


async def test_a_missing_service_fails_with_result_false_and_a_status(sim: Simulator) -> None:
    async with peer(sim) as client:
        await client.send(op="call_service", id="c1", service="/nope", args={})
        status = await client.receive(lambda m: m.get("op") == "status")
        response = await client.receive(lambda m: m.get("op") == "service_response")
    assert response["result"] is False and "does not exist" in response["values"]
    assert status["level"] == "error" and status["id"] == "c1"


async def test_an_unknown_op_gets_an_error_status(sim: Simulator) -> None:
    async with peer(sim) as client:
        await client.send(op="teleport", id="t1")
        status = await client.receive(lambda m: m.get("op") == "status")
    assert "Unknown operation" in status["msg"]


async def test_a_client_can_provide_a_service_to_other_clients(sim: Simulator) -> None:
    async with peer(sim) as server, peer(sim) as caller:
        await server.send(op="advertise_service", service="/add", type="example_interfaces/srv/AddTwoInts")
        await asyncio.sleep(0.05)
        await caller.send(op="call_service", id="sum", service="/add", args={"a": 2, "b": 3})
        request = await server.receive(lambda m: m.get("op") == "call_service")
        args = request["args"]
        await server.send(
            op="service_response",
            id=request["id"],
            service="/add",
            values={"sum": args["a"] + args["b"]},
            result=True,
        )
        response = await caller.receive(lambda m: m.get("op") == "service_response")
    assert response["values"] == {"sum": 5} and response["id"] == "sum"


async def test_an_action_goal_streams_feedback_then_its_result(sim: Simulator) -> None:
    async with peer(sim) as client:
        await client.send(
            op="send_action_goal",
            id="g1",
            action="/dock",
            action_type="irobot_create_msgs/action/Dock",
            args={},
            feedback=True,
        )
        feedback = await client.receive(lambda m: m.get("op") == "action_feedback")
        result = await client.receive(lambda m: m.get("op") == "action_result", timeout=10)
    assert feedback["id"] == "g1" and "sees_dock" in feedback["values"]
    assert (result["status"], result["result"], result["values"]) == (4, True, {"is_docked": True})


async def test_cancel_action_goal_ends_the_goal_as_canceled(sim: Simulator) -> None:
    async with peer(sim) as client:
        await client.send(
            op="send_action_goal",
            id="g2",
            action="/dock",
            action_type="irobot_create_msgs/action/Dock",
            args={},
            feedback=True,
        )
        await client.receive(lambda m: m.get("op") == "action_feedback")
        await client.send(op="cancel_action_goal", id="g2", action="/dock")
        result = await client.receive(lambda m: m.get("op") == "action_result")
    assert (result["status"], result["values"]) == (5, {"is_docked": False})
    assert sim.world.autopilot is None


async def test_a_wrong_action_type_is_refused(sim: Simulator) -> None:
    async with peer(sim) as client:
        await client.send(
            op="send_action_goal", id="g3", action="/dock", action_type="nav2_msgs/action/Spin", args={}
        )
        result = await client.receive(lambda m: m.get("op") == "action_result")
    assert result["result"] is False and "has type" in result["values"]


async def test_a_token_is_required_when_set() -> None:
    simulator = Simulator(load_profile("generic"), token="s3cret")
    await simulator.start()
    try:
        with pytest.raises(InvalidStatus):
            async with connect(simulator.url):
                pass
        async with connect(
            simulator.url, additional_headers={"Authorization": "Bearer s3cret"}
        ) as connection:
            await connection.send(json.dumps({"op": "call_service", "id": "n", "service": "/rosapi/nodes"}))
            assert json.loads(await connection.recv())["result"] is True
    finally:
        await simulator.stop()
