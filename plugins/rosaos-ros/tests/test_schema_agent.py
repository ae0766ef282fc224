"""A process agent that knows nothing of geometry_msgs/Twist looks it up and drives the simulator.

Real parts: the ROS driver's MCP server over HTTP with a bearer token, the rosbridge simulator
over a WebSocket, and the worker's ``run_job`` with a ``FunctionModel`` as the process model.
"""

from __future__ import annotations

import sys
from pathlib import Path

from rosaos.devices.serve import serve_http
from rosaos.drivers import DeviceContext
from rosaos.models.select import ModelSpec
from rosaos.processes.jobs import GrantedDevice, WorkerJob
from rosaos.processes.worker import run_job
from rosaos_ros.plugin import sim_backend
from rosaos_ros.server import build_server
from rosaos_ros.settings import RosSettings

HERE = str(Path(__file__).parent)
if HERE not in sys.path:
    sys.path.insert(0, HERE)

import ros_schema_models  # noqa: E402

TOKEN = "ros-device-token"


async def test_an_agent_looks_up_twist_and_publishes_a_valid_message(tmp_path: Path) -> None:
    ctx = DeviceContext(
        instance="turtlebot",
        description="TurtleBot 4 in the test arena",
        settings=RosSettings(profile="turtlebot4", publish_allow=["/cmd_vel"]),
        backend="sim",
        sim={"docked": False},
        data_dir=tmp_path,
    )
    backend = sim_backend(ctx)
    await backend.start()
    try:
        async with serve_http(build_server(ctx, backend), TOKEN) as served:
            job = WorkerJob(
                process_id=1,
                task="set linear.x to 0.1 on /cmd_vel",
                devices=[
                    GrantedDevice(
                        name="turtlebot", driver="ros", url=served.url, token=TOKEN, description="", prompt=""
                    )
                ],
                model=ModelSpec(model="python:ros_schema_models:looks_up_then_publishes", prefer_local=False),
                base_prompt="You are a test process.",
                timeout=30,
                request_limit=5,
                callback_url="http://127.0.0.1:9/event",
                callback_token="unused",
            )
            ros_schema_models.SEEN_TOOL_CALLS.clear()
            callback = await run_job(job)
        assert backend.simulator is not None
        world = backend.simulator.simulator.world
    finally:
        await backend.close()
    assert callback.status == "ok", callback.error
    calls = ros_schema_models.SEEN_TOOL_CALLS
    assert [name for name, _ in calls] == ["message_details", "publish"]
    zero = {"x": 0.0, "y": 0.0, "z": 0.0}
    assert calls[1][1]["msg"] == {"linear": {**zero, "x": 0.1}, "angular": zero}
    assert callback.output is not None and callback.output.startswith("published:")
    assert world.x > 0.0, "the robot did not move: the message was not a valid Twist"
