"""The offline kernel on a device notice: say it through the Reachy Mini when it matters, else stay quiet."""

from __future__ import annotations

from typing import Any

from fastmcp import FastMCP

from rosaos.events.plan import Plan
from rosaos.events.types import DeviceNotice
from rosaos.models.kernel_model import LocalIntentModel
from rosaos.notices.notice_text import render_notice

from .engine_turns import EngineKernel, callback, event
from .intents_support import home_world

BATTERY = DeviceNotice(
    device="turtlebot",
    message="turtlebot: battery at 12 %",
    data={"battery": 0.12},
    name="battery_low",
    driver="ros",
    importance="notify",
)


class Kernel(EngineKernel):
    """The offline engine whose launch_process records what it launches (task, devices, plan)."""

    def __init__(self, speaker: str | None) -> None:
        tools = FastMCP("kernel-tools")
        super().__init__(LocalIntentModel(home_world(), language="en", speaker=speaker), tools)
        self.launched: list[tuple[str, list[str], Plan | None]] = []

        @tools.tool
        async def launch_process(task: str, devices: list[str], plan: Plan | None = None) -> dict[str, Any]:
            """Start a process."""
            self.launched.append((task, devices, plan))
            return {"process_id": len(self.launched), "devices": devices, "state": "running"}


def test_a_notice_renders_for_an_llm_with_its_fields_and_its_message_quoted() -> None:
    text = render_notice(BATTERY)
    assert text == (
        '[Device notice] device=turtlebot name=battery_low importance=notify data={"battery": 0.12}\n'
        '"turtlebot: battery at 12 %"'
    )


def test_a_hand_posted_notice_keeps_the_one_line_shape_with_its_message_quoted() -> None:
    notice = DeviceNotice(device="door", message="the door opened")
    assert render_notice(notice) == '[Device notice] device=door importance=info "the door opened"'


async def test_a_notify_notice_is_said_through_the_speaker_device() -> None:
    kernel = Kernel(speaker="reachy")
    reply = await kernel.say(event("device_notice", BATTERY))
    [(task, devices, plan)] = kernel.launched
    assert devices == ["reachy"]
    assert task == "Tell the user: turtlebot: battery at 12 %"
    assert plan is not None and plan.quiet
    assert [(s.device, s.tool, s.args) for s in plan.steps] == [
        ("reachy", "speak", {"text": "turtlebot: battery at 12 %"})
    ]
    assert reply == "turtlebot: battery at 12 %"


async def test_the_speaking_process_ending_adds_no_reply() -> None:
    kernel = Kernel(speaker="reachy")
    await kernel.say(event("device_notice", BATTERY))
    task, _, plan = kernel.launched[0]
    ended = callback(1, task=task, plan=plan, output="turtlebot: battery at 12 %")
    assert (await kernel.say(ended)).strip() == ""


async def test_an_info_notice_gets_no_reply_and_launches_nothing() -> None:
    kernel = Kernel(speaker="reachy")
    docked = BATTERY.model_copy(
        update={"name": "docked", "importance": "info", "message": "turtlebot docked"}
    )
    assert (await kernel.say(event("device_notice", docked))).strip() == ""
    assert kernel.launched == []


async def test_without_a_speaker_a_notify_notice_is_a_text_reply() -> None:
    kernel = Kernel(speaker=None)
    assert await kernel.say(event("device_notice", BATTERY)) == "turtlebot: battery at 12 %"
    assert kernel.launched == []
