"""LocalPlanModel as a process agent's model: runs the job's typed plan on real MCP device servers."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from pydantic_ai import Agent
from pydantic_ai.mcp import MCPToolset
from pydantic_ai.messages import ToolCallPart
from pydantic_ai.toolsets import AbstractToolset

from rosaos.events.plan import Plan, PlanAnswer, PlanStep
from rosaos.models.process_model import NO_PLAN_REPLY, LocalPlanModel, plan_reply, resolve_tool
from rosaos.processes.jobs import GrantedDevice
from rosaos.processes.prompts import DEFAULT_PROCESS_PROMPT, process_system_prompt

from ..intents.intents_support import build_device_server


def granted(name: str, driver: str = "bulb") -> GrantedDevice:
    return GrantedDevice(
        name=name, driver=driver, url="http://unused", token="t", description=name, prompt="-"
    )


Task = tuple[str, Plan | None]
"""A job's task in words and its plan (a field of the job, as the kernel launched it)."""


async def run_process(
    task: Task, devices: dict[str, tuple[str, Any]], prefix: str | None = "_"
) -> tuple[str, list[ToolCallPart]]:
    """Run ``task`` the way the worker does: system prompt with the words, the plan to the model,
    one toolset per device.

    ``devices`` maps names to ``(driver, server)``; with several, tools are prefixed
    ``<device><prefix><tool>`` (the worker uses ``_``).
    """
    toolsets: list[AbstractToolset[Any]] = []
    for name, (_, server) in devices.items():
        toolset = MCPToolset(server)
        toolsets.append(toolset.prefixed(name + prefix[1:]) if len(devices) > 1 and prefix else toolset)
    words, plan = task
    prompt = process_system_prompt(
        DEFAULT_PROCESS_PROMPT, words, [granted(name, driver) for name, (driver, _) in devices.items()]
    )
    agent = Agent(LocalPlanModel(plan=plan), system_prompt=prompt, toolsets=toolsets)
    result = await agent.run(words)
    calls = [
        part for message in result.all_messages() for part in message.parts if isinstance(part, ToolCallPart)
    ]
    return result.output, calls


def task_for(*steps: PlanStep, answer: PlanAnswer | None = None) -> Task:
    plan = Plan(steps=list(steps), reply="Done: {result}.", failure="Sorry: {error}", answer=answer)
    return "Do the thing.", plan


async def test_a_plan_runs_in_order_and_ends_with_its_reply() -> None:
    state: dict[str, Any] = {"on": False, "brightness": 100}
    task = task_for(
        PlanStep(device="lamp", tool="turn_on"),
        PlanStep(device="lamp", tool="set_brightness", args={"brightness": 20}),
    )
    output, calls = await run_process(task, {"lamp": ("bulb", build_device_server("lamp", state))})
    assert [call.tool_name for call in calls] == ["turn_on", "set_brightness"]
    assert (state["on"], state["brightness"]) == (True, 20)
    assert output == "Done: on: true, brightness: 20."


@pytest.mark.parametrize("prefix", ["_", "__"])
async def test_prefixed_tool_names_are_resolved_by_device_and_tool(prefix: str) -> None:
    lamp: dict[str, Any] = {"on": False}
    fan: dict[str, Any] = {"on": False}
    task = task_for(PlanStep(device="fan", tool="turn_on"))
    servers = {
        "lamp": ("bulb", build_device_server("lamp", lamp)),
        "fan": ("bulb", build_device_server("fan", fan)),
    }
    _, calls = await run_process(task, servers, prefix=prefix)
    assert [call.tool_name for call in calls] == [f"fan{prefix}turn_on"]
    assert (lamp["on"], fan["on"]) == (False, True)


@pytest.mark.parametrize(("on", "reply"), [(True, "Yes, it is on."), (False, "No, it is off.")])
async def test_a_question_is_answered_from_the_state(on: bool, reply: str) -> None:
    answer = PlanAnswer(when={"on": True}, yes="Yes, it is on.", no="No, it is off.")
    task = task_for(PlanStep(device="lamp", tool="get_state"), answer=answer)
    output, _ = await run_process(task, {"lamp": ("bulb", build_device_server("lamp", {"on": on}))})
    assert output == reply


@pytest.mark.parametrize(
    ("state", "reply"),
    [
        ({"on": True, "brightness": 40}, "The lamp is on, at 40%."),
        ({"on": False, "brightness": 40}, "The lamp is off."),
        # A key the state lacks: the whole state is read instead of a reply with a hole in it.
        ({"on": True}, "lamp: on: true"),
    ],
)
async def test_a_driver_question_fills_its_reply_from_the_state(state: dict[str, Any], reply: str) -> None:
    answer = PlanAnswer(when={"on": True}, yes="The lamp is on, at {brightness}%.", no="The lamp is off.")
    plan = Plan(
        steps=[PlanStep(device="lamp", tool="get_state")],
        reply="-",
        answer=answer,
        fills_state=True,
    )
    output, _ = await run_process(
        ("How bright?", plan), {"lamp": ("bulb", build_device_server("lamp", state))}
    )
    assert output == reply


async def test_a_reply_that_does_not_fill_state_keeps_its_braces() -> None:
    # A command's reply quotes the user ("Done: say {hi}."): only {result} is filled there.
    plan = Plan(steps=[PlanStep(device="lamp", tool="get_state")], reply="Done: say {hi}.")
    output, _ = await run_process(
        ("Say.", plan), {"lamp": ("bulb", build_device_server("lamp", {"on": True}))}
    )
    assert output == "Done: say {hi}."


async def test_a_failing_tool_stops_the_plan_and_reports_the_error() -> None:
    state: dict[str, Any] = {"on": False}
    task = task_for(PlanStep(device="lamp", tool="turn_on"), PlanStep(device="lamp", tool="turn_off"))
    output, calls = await run_process(
        task, {"lamp": ("bulb", build_device_server("lamp", state, fail={"turn_on"}))}
    )
    assert [call.tool_name for call in calls] == ["turn_on"]
    assert output == "Sorry: turn_on failed: the device is offline"


async def test_a_tool_the_process_lacks_is_reported_not_guessed() -> None:
    task = task_for(PlanStep(device="lamp", tool="self_destruct"))
    output, calls = await run_process(task, {"lamp": ("bulb", build_device_server("lamp", {}))})
    assert calls == []
    assert output.startswith("Sorry: the tool self_destruct of lamp is not available to this process")


async def test_numbers_are_clamped_to_the_tool_bounds() -> None:
    state: dict[str, Any] = {}
    task = task_for(PlanStep(device="lamp", tool="set_brightness", args={"brightness": 150}))
    await run_process(task, {"lamp": ("bulb", build_device_server("lamp", state))})
    assert state["brightness"] == 100


async def test_an_attached_reachy_is_left_alone_unless_the_plan_speaks() -> None:
    lamp: dict[str, Any] = {"on": False}
    reachy: dict[str, Any] = {}
    task = task_for(PlanStep(device="lamp", tool="turn_on"))
    servers = {
        "reachy": ("reachy", build_device_server("reachy", reachy)),
        "lamp": ("bulb", build_device_server("lamp", lamp)),
    }
    output, calls = await run_process(task, servers)
    assert [call.tool_name for call in calls] == ["lamp_turn_on"]
    assert output == "Done: on: true."
    assert "last_spoken" not in reachy


async def test_a_plan_that_says_something_speaks_once() -> None:
    reachy: dict[str, Any] = {}
    task = task_for(PlanStep(device="reachy", tool="speak", args={"text": "Good morning"}))
    _, calls = await run_process(task, {"reachy": ("reachy", build_device_server("reachy", reachy))})
    assert [call.tool_name for call in calls] == ["speak"]
    assert reachy["last_spoken"] == "Good morning"


async def test_a_task_without_a_plan_says_how_to_configure_an_llm() -> None:
    output, calls = await run_process(
        ("Patrol the house.", None), {"lamp": ("bulb", build_device_server("lamp", {}))}
    )
    assert (output, calls) == (NO_PLAN_REPLY, [])


def test_tool_resolution_prefers_the_device_prefix() -> None:
    assert resolve_tool("lamp", "turn_on", ["turn_on", "lamp_turn_on"]) == "lamp_turn_on"
    assert resolve_tool("lamp", "turn_on", ["lamp__turn_on"]) == "lamp__turn_on"
    assert resolve_tool("lamp", "turn_on", ["turn_on"]) == "turn_on"
    assert resolve_tool("lamp", "turn_on", ["fan_turn_on"]) is None


async def test_a_plan_from_the_matcher_changes_a_real_tapo_bulb(tmp_path: Path) -> None:
    pytest.importorskip("rosaos_tapo")
    from rosaos.config import DeviceConfig, RosaosConfig
    from rosaos.devices.serve import open_device
    from rosaos.devices.world import build_world
    from rosaos.intents.grammar.vocabulary import device_vocabularies
    from rosaos.intents.understanding.matching import IntentMatcher
    from rosaos.plugins import load_drivers

    config = RosaosConfig(
        devices={
            "kitchen_light": DeviceConfig(
                driver="tapo",
                description="Ceiling light in the kitchen",
                sim={"on": False, "brightness": 100},
            )
        }
    )
    world = build_world(config, load_drivers())
    [process] = (
        IntentMatcher(device_vocabularies(world)).match("Set the kitchen light to 30 percent").processes
    )
    async with open_device(world.get("kitchen_light"), tmp_path) as device:
        output, calls = await run_process(
            (process.summary, process.plan), {"kitchen_light": ("tapo", device.server)}
        )
        state = await device.backend.state()  # type: ignore[attr-defined]
    assert [call.tool_name for call in calls] == ["set_brightness"]
    assert (state.on, state.brightness) == (True, 30)
    assert output == "Done: set the kitchen light to 30 percent."


async def test_the_devices_are_read_from_instructions_too() -> None:
    # The worker may pass the process prompt as instructions rather than a system prompt.
    lamp: dict[str, Any] = {"on": False}
    reachy: dict[str, Any] = {}
    words, plan = task_for(PlanStep(device="lamp", tool="turn_on"))
    prompt = process_system_prompt(
        DEFAULT_PROCESS_PROMPT, words, [granted("lamp"), granted("reachy", "reachy")]
    )
    toolsets = [
        MCPToolset(build_device_server("lamp", lamp)).prefixed("lamp"),
        MCPToolset(build_device_server("reachy", reachy)).prefixed("reachy"),
    ]
    result = await Agent(LocalPlanModel(plan=plan), instructions=prompt, toolsets=toolsets).run("Go.")
    assert (lamp["on"], result.output) == (True, "Done: on: true.")
    assert "last_spoken" not in reachy


def test_a_command_whose_device_says_what_it_did_is_answered_with_those_words() -> None:
    """ "Done: next song." says what was asked; the device's ``message`` says what happened."""
    plan = Plan(steps=[PlanStep(device="speaker", tool="next_track")], reply="Done: next song.", failure="-")
    said = {"message": "Playing Blue in Green by Miles Davis", "state": {"is_playing": True}}
    assert plan_reply(plan, [said]) == "Done: next song. Playing Blue in Green by Miles Davis."
    # Its JSON text, as some MCP servers return it, reads the same; the same words once.
    volume = '{"message": "Volume 40% → 55%.", "state": {"volume": 55}}'
    assert plan_reply(plan, [volume, volume]) == "Done: next song. Volume 40% → 55%."
    # A bare state word ("awake", the Reachy's) reads as a sentence of its own.
    assert plan_reply(plan, [{"message": "awake"}]) == "Done: next song. Awake."


@pytest.mark.parametrize(
    "result",
    [{"on": True}, "ok", {"message": ""}, {"message": 7}, {"message": "x" * 500}],
)
def test_a_result_without_short_words_of_its_own_leaves_the_plain_reply(result: Any) -> None:
    plan = Plan(steps=[PlanStep(device="lamp", tool="turn_on")], reply="Done: turn it on.", failure="-")
    assert plan_reply(plan, [result]) == "Done: turn it on."


def test_an_answer_to_a_question_is_not_padded_with_the_devices_words() -> None:
    answer = PlanAnswer(when={"is_playing": True}, yes="Yes, it plays.", no="No, it is quiet.")
    plan = Plan(steps=[PlanStep(device="speaker", tool="get_state")], reply="-", failure="-", answer=answer)
    assert plan_reply(plan, [{"is_playing": True, "message": "Playing So What."}]) == "Yes, it plays."
