"""``rosaos-ros-sim``: the simulator on its own, as a command."""

from __future__ import annotations

import asyncio
import json
import socket
import sys

from websockets.asyncio.client import connect

from rosaos_ros.sim.cli import main


def test_an_unknown_profile_is_a_usage_error() -> None:
    assert main(["--profile", "spot"]) == 2


def test_bad_initial_state_names_the_allowed_keys() -> None:
    assert main(["--profile", "generic", "--state", '{"heading": 1}']) == 2


async def test_the_command_serves_rosbridge_until_stopped() -> None:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosaos_ros.sim",
        "--profile",
        "puppypi",
        "--port",
        str(port),
        "--token",
        "cli-test-token",
        stdout=asyncio.subprocess.PIPE,
    )
    try:
        assert process.stdout is not None
        banner = await asyncio.wait_for(process.stdout.readline(), 30)
        async with connect(f"ws://127.0.0.1:{port}?token=cli-test-token") as connection:
            await connection.send(
                json.dumps({"op": "call_service", "id": "1", "service": "/rosapi/get_param_names"})
            )
            names = json.loads(await connection.recv())["values"]["names"]
    finally:
        process.terminate()
        await process.wait()
    assert b"puppypi" in banner and "/puppy_control:gait.mode" in names
