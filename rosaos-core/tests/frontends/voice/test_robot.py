"""The robot's side: turn toward the speaker, wave, and know when it is speaking."""

from __future__ import annotations

import asyncio
import logging
import math
import time
from typing import Any

import pytest
from fastmcp import FastMCP
from fastmcp.exceptions import ToolError

from rosaos.devices.client import DeviceClient
from rosaos.frontends.voice.robot import (
    ECHO_TAIL_SECONDS,
    NoRobot,
    ReachyLink,
    doa_to_yaw,
    find_reachy,
)
from rosaos.kernel.api.kernel_client import KernelUnavailable


@pytest.mark.parametrize(("doa", "yaw"), [(math.pi / 2, 0.0), (math.pi / 3, 30.0), (2 * math.pi / 3, -30.0)])
def test_the_direction_of_arrival_becomes_a_head_yaw(doa: float, yaw: float) -> None:
    assert doa_to_yaw(doa) == pytest.approx(yaw)


def test_the_yaw_is_bounded() -> None:
    assert doa_to_yaw(0.0) == 60.0 and doa_to_yaw(math.pi) == -60.0


def fake_reachy(calls: list[tuple[str, dict[str, Any]]], fail: bool = False) -> FastMCP:
    """The companion tool the voice front end calls on wake, recording its arguments."""
    mcp = FastMCP("reachy")

    @mcp.tool
    def set_listening(on: bool, direction: float | None = None, seconds: float = 10.0) -> str:
        if fail:
            raise ToolError("the companion is asleep")
        calls.append(("set_listening", {"on": on, "direction": direction, "seconds": seconds}))
        return "ok"

    return mcp


async def test_on_wake_the_robot_listens_turned_toward_the_speaker() -> None:
    calls: list[tuple[str, dict[str, Any]]] = []
    link = ReachyLink(DeviceClient.in_process(fake_reachy(calls)))
    await link.woke(math.pi / 3, 8.0)
    assert calls == [("set_listening", {"on": True, "direction": 30.0, "seconds": 8.0})]
    await link.listened()
    assert calls[-1] == ("set_listening", {"on": False, "direction": None, "seconds": 10.0})


async def test_without_a_direction_it_listens_where_it_faces() -> None:
    calls: list[tuple[str, dict[str, Any]]] = []
    await ReachyLink(DeviceClient.in_process(fake_reachy(calls))).woke(None, 500.0)
    assert calls == [("set_listening", {"on": True, "direction": None, "seconds": 120.0})]  # bounded


async def test_a_failing_gesture_is_logged_once(caplog: pytest.LogCaptureFixture) -> None:
    link = ReachyLink(DeviceClient.in_process(fake_reachy([], fail=True)))
    with caplog.at_level(logging.WARNING):
        await link.woke(None, 8.0)
        await link.woke(None, 8.0)
    ours = [r for r in caplog.records if r.name == "rosaos.frontends.voice.robot"]
    assert len(ours) == 1 and "set_listening" in ours[0].getMessage()


def test_speaking_until_mutes_until_then() -> None:
    link = ReachyLink(DeviceClient.in_process(FastMCP("r")))
    link.observe({"speaking_until": 1_000.0, "last_spoken": "ok"}, now=990.0)
    assert link.muted(999.9) and link.muted(1_000.0 + ECHO_TAIL_SECONDS - 0.01)
    assert not link.muted(1_000.0 + ECHO_TAIL_SECONDS + 0.01)


def test_speaking_true_mutes_for_now() -> None:
    link = ReachyLink(DeviceClient.in_process(FastMCP("r")))
    link.observe({"speaking": True}, now=500.0)
    assert link.muted(500.2)
    assert not link.muted(502.0)


def test_a_new_last_spoken_mutes_for_about_as_long_as_it_takes_to_say() -> None:
    link = ReachyLink(DeviceClient.in_process(FastMCP("r")))
    link.observe({"last_spoken": ""}, now=100.0)  # the first reading is history, not speech
    assert not link.muted(100.1)
    link.observe({"last_spoken": "The kitchen light is on now."}, now=101.0)  # 28 characters: ~2 s
    assert link.muted(102.5)
    assert not link.muted(104.0)


def test_no_robot_never_mutes() -> None:
    assert NoRobot().muted(0.0) is False


class FakeKernel:
    def __init__(self, devices: list[dict[str, Any]] | None) -> None:
        self.devices = devices

    async def request(self, method: str, path: str, **kwargs: Any) -> Any:
        if self.devices is None:
            raise KernelUnavailable("cannot reach the rosaOS kernel")
        return self.devices


async def test_a_served_reachy_instance_is_found_through_the_kernel() -> None:
    kernel = FakeKernel(
        [
            {"name": "kitchen_light", "driver": "tapo", "url": "http://127.0.0.1:1/mcp"},
            {"name": "reachy", "driver": "reachy", "url": "http://127.0.0.1:2/mcp", "state": {"awake": True}},
        ]
    )
    link = await find_reachy(kernel, "token")  # type: ignore[arg-type]
    assert isinstance(link, ReachyLink) and link.device.url == "http://127.0.0.1:2/mcp"


@pytest.mark.parametrize(
    "devices",
    [
        [],
        [{"name": "reachy", "driver": "reachy", "url": None, "state": None}],
        [{"name": "reachy", "driver": "reachy", "url": "http://x/mcp", "state": {"implemented": False}}],
        None,
    ],
)
async def test_without_a_served_reachy_there_is_no_robot(devices: list[dict[str, Any]] | None) -> None:
    assert isinstance(await find_reachy(FakeKernel(devices), "token"), NoRobot)  # type: ignore[arg-type]


async def test_saying_a_reply_calls_speak_and_stops_listening_until_it_is_said() -> None:
    said: list[str] = []
    mcp = FastMCP("reachy")

    @mcp.tool
    def speak(text: str) -> dict[str, Any]:
        said.append(text)
        return {"spoken": text, "seconds": 2.0, "speaking_until": 5_000.0}

    link = ReachyLink(DeviceClient.in_process(mcp))
    assert await link.say("Done: turn on the kitchen light.") is True
    assert said == ["Done: turn on the kitchen light."]
    assert link.muted(4_999.0) and link.muted(5_000.0 + ECHO_TAIL_SECONDS - 0.01)


async def test_a_reply_the_robot_cannot_say_is_reported_not_raised() -> None:
    assert await ReachyLink(DeviceClient.in_process(FastMCP("r"))).say("hello") is False


async def test_a_barge_in_listens_again_at_once_and_stops_the_robot() -> None:
    mcp = FastMCP("reachy")
    stops: list[bool] = []

    @mcp.tool
    def speak(text: str) -> dict[str, Any]:
        return {"spoken": text, "seconds": 20.0, "speaking_until": 9e9}

    @mcp.tool
    def stop_speaking() -> dict[str, Any]:
        stops.append(True)
        return {"stopped": True, "cut_off": "a long answer"}

    link = ReachyLink(DeviceClient.in_process(mcp))
    await link.say("a long answer")
    assert link.muted(1e9)
    link.unmute()
    assert not link.muted(1e9)
    assert await link.stop_speaking() is True and stops == [True]


async def test_a_state_read_while_the_barge_in_stop_is_on_its_way_does_not_mute_again() -> None:
    # A busy machine: the driver answers get_state (still speaking) before it has run stop_speaking.
    mcp = FastMCP("reachy")
    speaking = {"speaking": True, "speaking_until": 9e9, "last_spoken": "a long answer"}
    stop_may_finish = asyncio.Event()
    polls_while_stopping: list[int] = []
    two_polls = asyncio.Event()

    @mcp.tool
    def speak(text: str) -> dict[str, Any]:
        return {"spoken": text, "seconds": 20.0, "speaking_until": 9e9}

    @mcp.tool
    def get_state() -> dict[str, Any]:
        if not stop_may_finish.is_set():
            polls_while_stopping.append(1)
            if len(polls_while_stopping) >= 2:  # the first one's answer has been looked at
                two_polls.set()
        return dict(speaking)

    @mcp.tool
    async def stop_speaking() -> dict[str, Any]:
        await stop_may_finish.wait()
        speaking.update(speaking=False, speaking_until=None)
        return {"stopped": True, "cut_off": "a long answer"}

    link = ReachyLink(DeviceClient.in_process(mcp))
    await link.say("a long answer")
    link.unmute()
    stopping = asyncio.create_task(link.stop_speaking())
    following = asyncio.create_task(link.follow())
    try:
        await asyncio.wait_for(two_polls.wait(), 60)
        assert not link.muted(time.time()), "a state asked before the robot stopped muted it again"
        stop_may_finish.set()
        assert await stopping is True
        assert not link.muted(time.time())
    finally:
        following.cancel()
        await asyncio.gather(following, return_exceptions=True)


async def test_stopping_a_robot_without_the_tool_is_reported_not_raised() -> None:
    assert await ReachyLink(DeviceClient.in_process(FastMCP("r"))).stop_speaking() is False
    assert await NoRobot().stop_speaking() is False
