"""The offline kernel on a ``[Device notice]``: say it through the Reachy Mini when it matters, else stay quiet."""

from __future__ import annotations

from typing import Any

from fastmcp import FastMCP
from intents_support import home_world
from pydantic_ai import Agent
from pydantic_ai.mcp import MCPToolset

from rosaos.intents.planning.plan import decode_plan
from rosaos.kernel.events import DeviceNotice
from rosaos.kernel.notice_text import read_notice, render_notice
from rosaos.models.kernel_model import LocalIntentModel
from rosaos.processes.jobs import WorkerCallback

BATTERY = DeviceNotice(
    device="turtlebot",
    message="turtlebot: battery at 12 %",
    data={"battery": 0.12},
    name="battery_low",
    driver="ros",
    importance="notify",
)


def _agent(speaker: str | None) -> tuple[Agent[None, str], list[tuple[str, list[str]]]]:
    tools = FastMCP("kernel-tools")
    launched: list[tuple[str, list[str]]] = []

    @tools.tool
    async def launch_process(task: str, devices: list[str]) -> dict[str, Any]:
        """Start a process."""
        launched.append((task, devices))
        return {"process_id": len(launched), "devices": devices, "state": "running"}

    model = LocalIntentModel(home_world(), language="en", speaker=speaker)
    return Agent(model, toolsets=[MCPToolset(tools)]), launched


def test_a_notice_renders_and_reads_back() -> None:
    text = render_notice(BATTERY)
    assert text.startswith(
        '[Device notice] device=turtlebot name=battery_low importance=notify data={"battery": 0.12}'
    )
    read = read_notice(text.removeprefix("[Device notice] "))
    assert (read.device, read.name, read.importance, read.data, read.message) == (
        "turtlebot",
        "battery_low",
        "notify",
        {"battery": 0.12},
        "turtlebot: battery at 12 %",
    )


def test_a_hand_posted_notice_keeps_the_one_line_shape_with_its_message_quoted() -> None:
    notice = DeviceNotice(device="door", message="the door opened")
    assert render_notice(notice) == '[Device notice] device=door importance=info "the door opened"'
    assert read_notice('device=door importance=info "the door opened"').message == "the door opened"


async def test_a_notify_notice_is_said_through_the_speaker_device() -> None:
    agent, launched = _agent(speaker="reachy")
    result = await agent.run(render_notice(BATTERY))
    assert len(launched) == 1
    task, devices = launched[0]
    assert devices == ["reachy"]
    plan = decode_plan(task)
    assert plan is not None and plan.quiet
    assert [(s.device, s.tool, s.args) for s in plan.steps] == [
        ("reachy", "speak", {"text": "turtlebot: battery at 12 %"})
    ]
    assert result.output == "turtlebot: battery at 12 %"


async def test_the_speaking_process_ending_adds_no_reply() -> None:
    agent, launched = _agent(speaker="reachy")
    await agent.run(render_notice(BATTERY))
    callback = WorkerCallback(
        process_id=1, status="ok", output="turtlebot: battery at 12 %", task=launched[0][0]
    )
    rendered = f"[Worker callback] worker=1 status=ok task={callback.task!r}\noutput: {callback.output}"
    assert (await agent.run(rendered)).output.strip() == ""


async def test_an_info_notice_gets_no_reply_and_launches_nothing() -> None:
    agent, launched = _agent(speaker="reachy")
    docked = BATTERY.model_copy(
        update={"name": "docked", "importance": "info", "message": "turtlebot docked"}
    )
    assert (await agent.run(render_notice(docked))).output.strip() == ""
    assert launched == []


async def test_without_a_speaker_a_notify_notice_is_a_text_reply() -> None:
    agent, launched = _agent(speaker=None)
    assert (await agent.run(render_notice(BATTERY))).output == "turtlebot: battery at 12 %"
    assert launched == []
