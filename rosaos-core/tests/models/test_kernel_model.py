"""LocalIntentModel as the kernel agent's model, with a real MCP launch_process tool in-process.

Each turn hands the engine a typed event, as the kernel loop does (``engine_turns``)."""

from __future__ import annotations

from typing import Any

import pytest
from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from pydantic_ai import Agent
from pydantic_ai.messages import ToolCallPart

from rosaos.events.plan import Plan
from rosaos.models.kernel_model import LocalIntentModel

from ..intents.engine_turns import EngineKernel, callback, error, notice, said
from ..intents.intents_support import home_world


class Kernel(EngineKernel):
    """The offline engine with a launch_process that records what it is asked (task, devices, plan)."""

    def __init__(self, model: LocalIntentModel) -> None:
        tools = FastMCP("kernel-tools")
        super().__init__(model, tools)
        self.launched: list[tuple[str, list[str], Plan | None]] = []
        self.held: dict[str, int] = {}

        @tools.tool
        async def launch_process(task: str, devices: list[str], plan: Plan | None = None) -> dict[str, Any]:
            """Start a process; refuses a device another process holds."""
            for device in devices:
                if device in self.held:
                    raise ToolError(f"{device} is held by process {self.held[device]}; wait for its callback")
            self.launched.append((task, devices, plan))
            return {"process_id": len(self.launched), "devices": devices, "state": "running"}


@pytest.fixture(scope="module")
def model() -> LocalIntentModel:
    return LocalIntentModel(home_world(), language="en")


@pytest.fixture
def kernel(model: LocalIntentModel) -> Kernel:
    return Kernel(model)


async def test_a_command_launches_a_process_with_the_plan_and_acknowledges(kernel: Kernel) -> None:
    reply = await kernel.say("Turn on the kitchen light")
    [(task, devices, plan)] = kernel.launched
    assert devices == ["kitchen_light"]
    assert task == "Turn on the kitchen light."
    assert plan is not None
    assert [(step.device, step.tool) for step in plan.steps] == [("kitchen_light", "turn_on")]
    assert reply == "On it: turn on the kitchen light."


async def test_all_the_lights_are_parallel_launches_in_one_response(kernel: Kernel) -> None:
    reply = await kernel.say("Turn off all the lights")
    first = kernel.responses()[0]
    assert [part.tool_name for part in first.parts if isinstance(part, ToolCallPart)] == [
        "launch_process"
    ] * 3
    assert sorted(devices[0] for _, devices, _ in kernel.launched) == [
        "bedroom_light",
        "kitchen_light",
        "living_room_lamp",
    ]
    assert reply == "On it: turn off all the lights."


async def test_two_commands_are_two_processes(kernel: Kernel) -> None:
    await kernel.say("Turn on the kitchen light and play some jazz")
    assert [devices for _, devices, _ in kernel.launched] == [["kitchen_light"], ["speaker"]]


@pytest.mark.parametrize(
    ("event", "reply"),
    [
        (
            "Turn off the light",
            "Which one do you mean: kitchen light, living room lamp or bedroom light?",
        ),
        ("Turn on the garage light", 'I don\'t know "garage light".'),
        ("Tell the drone to take off", "I have no drone to control"),
    ],
)
async def test_nothing_is_launched_on_a_guess(kernel: Kernel, event: str, reply: str) -> None:
    assert (await kernel.say(event)).startswith(reply)
    assert kernel.launched == []


async def test_a_refused_launch_is_relayed(kernel: Kernel) -> None:
    kernel.held["kitchen_light"] = 7
    reply = await kernel.say("Turn on the kitchen light")
    assert reply == "I couldn't start that: kitchen_light is held by process 7; wait for its callback"


async def test_the_answer_to_which_one_completes_the_command(kernel: Kernel) -> None:
    await kernel.say("Turn off the light")
    reply = await kernel.say("the bedroom light")
    [(_, devices, plan)] = kernel.launched
    assert devices == ["bedroom_light"]
    assert plan is not None
    assert plan.steps[0].tool == "turn_off"
    assert reply == "On it: turn off the light (bedroom light)."


async def test_a_question_launches_a_state_read(kernel: Kernel) -> None:
    reply = await kernel.say("Is the kitchen light on?")
    [(_, _, plan)] = kernel.launched
    assert plan is not None
    assert plan.answer is not None
    assert reply == "Checking the kitchen light."


async def test_a_callback_output_is_the_reply(kernel: Kernel) -> None:
    event = callback(3, task="Is the kitchen light on?", output="No, the kitchen light is off.")
    assert await kernel.say(event) == "No, the kitchen light is off."
    assert kernel.launched == []


async def test_a_failed_callback_uses_the_plan_failure_text(kernel: Kernel, model: LocalIntentModel) -> None:
    [process] = model.match("Turn on the kitchen light").processes
    event = callback(4, status="error", task=process.summary, plan=process.plan, error="the bulb is offline")
    assert await kernel.say(event) == 'Sorry, "turn on the kitchen light" failed: the bulb is offline'


async def test_a_failed_callback_without_a_plan_still_says_what_failed(kernel: Kernel) -> None:
    event = callback(5, status="timeout", task="Patrol the house", error="ran past its timeout")
    assert await kernel.say(event) == "Sorry, that didn't work (timeout): ran past its timeout"


async def test_info_notices_are_quiet_and_errors_acknowledged_without_acting(kernel: Kernel) -> None:
    # A notice without importance=notify is not worth interrupting anyone (test_notice_plan.py).
    assert (await kernel.say(notice("turtlebot", "battery low"))).strip() == ""
    assert await kernel.say(error("the web page lost its connection")) == (
        "Something went wrong: the web page lost its connection"
    )
    assert kernel.launched == []


async def test_without_a_launch_tool_it_says_so(model: LocalIntentModel) -> None:
    result = await Agent(model).run("Turn on the kitchen light")  # a bare prompt is typed text
    assert "no launch_process tool" in result.output


def test_handles_event_is_true_only_for_what_it_answers_exactly(model: LocalIntentModel) -> None:
    assert model.handles_event(said("Turn on the kitchen light"))
    assert not model.handles_event(said("Turn off the light"))
    assert not model.handles_event(said("What's the weather like?"))
    [process] = model.match("Turn on the kitchen light").processes
    assert model.handles_event(callback(1, task=process.summary, plan=process.plan, output="Done."))
    assert not model.handles_event(callback(1, task="free-form", output="Done."))


async def test_yes_to_did_you_mean_launches_the_suggested_command(kernel: Kernel) -> None:
    asked = await kernel.say("could the kitchen light go off")
    assert asked == "Did you mean: turn off the kitchen light?"
    assert kernel.launched == []
    await kernel.say("yes")
    [(_, devices, plan)] = kernel.launched
    assert devices == ["kitchen_light"]
    assert plan is not None and plan.steps[0].tool == "turn_off"
