"""Process agents on the ROS driver: a worker job, its FunctionModel, the driver's MCP server.

Real parts: the driver's MCP server over HTTP with a bearer token, the rosbridge simulator over a
WebSocket, and the worker's ``run_job`` (with its device session headers) with a ``FunctionModel``.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from rosaos.devices.serve import serve_http
from rosaos.drivers import DeviceContext
from rosaos.events.callback import WorkerCallback
from rosaos.models.select import ModelSpec
from rosaos.processes.jobs import GrantedDevice, WorkerJob
from rosaos.processes.worker import run_job
from rosaos_ros.plugin import sim_backend
from rosaos_ros.server import build_server
from rosaos_ros.settings import RosSettings
from rosaos_ros.sim.world import DiffDriveWorld

from . import ros_schema_models

TOKEN = "ros-device-token"


async def run_on_robot(
    tmp_path: Path, task: str, model: str, *, vision: bool | None = None, **settings: Any
) -> tuple[WorkerCallback, DiffDriveWorld]:
    """Serve a simulated TurtleBot over HTTP, run one worker job on it, return how it ended."""
    ctx = DeviceContext(
        instance="turtlebot",
        description="TurtleBot 4 in the test arena",
        settings=RosSettings(profile="turtlebot4", **settings),
        backend="sim",
        sim={"docked": False},
        data_dir=tmp_path,
    )
    backend = sim_backend(ctx)
    await backend.start()
    try:
        async with serve_http(build_server(ctx, backend), TOKEN) as served:
            device = GrantedDevice(
                name="turtlebot", driver="ros", url=served.url, token=TOKEN, description="", prompt=""
            )
            job = WorkerJob(
                process_id=1,
                task=task,
                devices=[device],
                model=ModelSpec(
                    model=f"python:{ros_schema_models.__name__}:{model}",
                    prefer_local=False,
                    vision=vision,
                    image_max_px=64,
                ),
                base_prompt="You are a test process.",
                timeout=30,
                request_limit=5,
                kernel_url="http://127.0.0.1:9",
                kernel_token="unused",
            )
            callback = await run_job(job)
        assert backend.simulator is not None
        return callback, backend.simulator.simulator.world
    finally:
        await backend.close()


async def test_an_agent_looks_up_twist_and_publishes_a_valid_message(tmp_path: Path) -> None:
    ros_schema_models.SEEN_TOOL_CALLS.clear()
    callback, world = await run_on_robot(
        tmp_path, "set linear.x to 0.1 on /cmd_vel", "looks_up_then_publishes", publish_allow=["/cmd_vel"]
    )
    assert callback.status == "ok", callback.error
    calls = ros_schema_models.SEEN_TOOL_CALLS
    assert [name for name, _ in calls] == ["message_details", "publish"]
    zero = {"x": 0.0, "y": 0.0, "z": 0.0}
    assert calls[1][1]["msg"] == {"linear": {**zero, "x": 0.1}, "angular": zero}
    assert callback.output is not None and callback.output.startswith("published:")
    assert world.x > 0.0, "the robot did not move: the message was not a valid Twist"


async def test_a_model_that_takes_images_gets_the_picture_downscaled(tmp_path: Path) -> None:
    callback, _ = await run_on_robot(tmp_path, "take a picture", "sees_pictures", vision=True)
    assert callback.status == "ok", callback.error
    seen = json.loads(callback.output or "")
    assert len(seen["images"]) == 1
    width, height = seen["images"][0]
    assert max(width, height) <= 64 < max(seen["report"]["width"], seen["report"]["height"])
    assert seen["report"]["image"].endswith(".jpg") and seen["report"]["image_sent"] is True
    assert (tmp_path / "images" / seen["report"]["image"]).is_file()


async def test_a_text_only_model_gets_the_path_and_no_image(tmp_path: Path) -> None:
    callback, _ = await run_on_robot(tmp_path, "take a picture", "text_only")
    assert callback.status == "ok", callback.error
    seen = json.loads(callback.output or "")
    assert seen["images"] == [] and seen["report"]["image"].endswith(".jpg")
    assert "image_sent" not in seen["report"]


async def test_config_vision_false_overrides_the_profile(tmp_path: Path) -> None:
    callback, _ = await run_on_robot(tmp_path, "take a picture", "sees_pictures", vision=False)
    assert json.loads(callback.output or "")["images"] == []
