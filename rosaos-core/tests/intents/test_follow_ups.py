"""Follow-ups in the offline engine: planned from one sentence, carried by the callback, launched only on success."""

from __future__ import annotations

from typing import Any

import pytest
from fastmcp import FastMCP
from pydantic_ai import Agent
from pydantic_ai.mcp import MCPToolset

from rosaos.events.plan import Plan
from rosaos.events.types import Event
from rosaos.intents.planning.follow_ups import plan_follow_up, unmet_output
from rosaos.models.kernel_model import LocalIntentModel

from .engine_turns import EngineKernel, callback
from .intents_support import home_world

WHEN_FOUND = "Turn on the kitchen light, and when you find someone turn off the bedroom light"


@pytest.fixture(scope="module")
def model() -> LocalIntentModel:
    return LocalIntentModel(home_world(), language="en")


class Kernel(EngineKernel):
    """The offline engine whose launch_process records what it launches (task, devices, plan)."""

    def __init__(self, model: LocalIntentModel) -> None:
        tools = FastMCP("kernel-tools")
        super().__init__(model, tools)
        self.launched: list[tuple[str, list[str], Plan | None]] = []

        @tools.tool
        async def launch_process(task: str, devices: list[str], plan: Plan | None = None) -> dict[str, Any]:
            """Start a process."""
            self.launched.append((task, devices, plan))
            return {"process_id": len(self.launched), "devices": devices, "state": "running"}

    def first_callback(self, **fields: Any) -> Event:
        """The callback of the first process launched, carrying its task and plan."""
        task, _, plan = self.launched[0]
        return callback(1, task=task, plan=plan, **fields)


def test_then_plans_one_process_that_carries_the_next(model: LocalIntentModel) -> None:
    result = plan_follow_up("Turn on the kitchen light, then play some jazz", model.match)
    assert result is not None
    [process] = result.processes
    assert process.devices == ("kitchen_light",)
    follow_up = process.plan.then
    assert follow_up is not None and follow_up.when is None
    assert [(item.devices, [s.tool for s in item.plan.steps]) for item in follow_up.launches] == [
        (["speaker"], ["play"])
    ]
    assert process.plan.ack.endswith("Then I'll play some jazz.")


def test_a_condition_about_finding_waits_for_found(model: LocalIntentModel) -> None:
    result = plan_follow_up(WHEN_FOUND, model.match, literal=model.matcher.literal)
    assert result is not None
    follow_up = result.processes[0].plan.then
    assert follow_up is not None
    assert follow_up.when == {"found": True}
    assert follow_up.launches[0].devices == ["bedroom_light"]
    assert follow_up.unmet == "I did not find anyone, so I did not turn off the bedroom light."


def test_a_chain_carries_its_last_step_inside_the_second(model: LocalIntentModel) -> None:
    result = plan_follow_up(
        "Turn on the kitchen light, then turn off the bedroom light, then play some jazz", model.match
    )
    assert result is not None
    second = result.processes[0].plan.then
    assert second is not None and second.launches[0].devices == ["bedroom_light"]
    third = second.launches[0].plan.then
    assert third is not None and third.launches[0].devices == ["speaker"]


@pytest.mark.parametrize(
    "text", ["Turn on the kitchen light and play some jazz", "Turn on the kitchen light", "then play"]
)
def test_a_sentence_without_a_follow_up_is_left_to_the_matcher(model: LocalIntentModel, text: str) -> None:
    assert plan_follow_up(text, model.match) is None


def test_the_condition_is_judged_on_the_newest_result_that_has_the_key(model: LocalIntentModel) -> None:
    result = plan_follow_up(WHEN_FOUND, model.match)
    assert result is not None
    plan = result.processes[0].plan
    unmet = "I did not find anyone, so I did not turn off the bedroom light."
    assert unmet_output(plan, [{"on": True}, {"found": True, "x": 1.0}]) is None
    assert unmet_output(plan, [{"found": True}, '{"found": false}']) == unmet
    assert unmet_output(plan, [{"on": True}]) == unmet  # nothing said "found": never on a guess


async def test_the_kernel_launches_the_first_step_only(model: LocalIntentModel) -> None:
    kernel = Kernel(model)
    reply = await kernel.say(WHEN_FOUND)
    [(_, devices, plan)] = kernel.launched
    assert devices == ["kitchen_light"]
    assert "When I find someone, I'll turn off the bedroom light." in reply
    assert plan is not None and plan.then is not None


async def test_a_successful_callback_launches_the_follow_up_and_says_both(model: LocalIntentModel) -> None:
    kernel = Kernel(model)
    await kernel.say(WHEN_FOUND)
    reply = await kernel.say(kernel.first_callback(output="Found a person at (-2.5, 0.5)."))
    assert [devices for _, devices, _ in kernel.launched] == [["kitchen_light"], ["bedroom_light"]]
    follow_up = kernel.launched[1][2]
    assert follow_up is not None and [s.tool for s in follow_up.steps] == ["turn_off"]
    assert reply.startswith("Found a person at (-2.5, 0.5).")
    assert "turn off the bedroom light" in reply.lower()


async def test_a_failed_callback_launches_nothing_and_says_so(model: LocalIntentModel) -> None:
    kernel = Kernel(model)
    await kernel.say(WHEN_FOUND)
    reply = await kernel.say(kernel.first_callback(status="error", error="kitchen_light: offline"))
    assert len(kernel.launched) == 1
    assert "offline" in reply
    assert reply.endswith("offline. So I did not turn off the bedroom light.")


async def test_an_unmet_condition_launches_nothing(model: LocalIntentModel) -> None:
    kernel = Kernel(model)
    await kernel.say(WHEN_FOUND)
    unmet = "I did not find anyone, so I did not turn off the bedroom light."
    reply = await kernel.say(kernel.first_callback(output=unmet))
    assert len(kernel.launched) == 1
    assert reply == unmet


async def test_a_terminated_first_step_cancels_the_follow_up(model: LocalIntentModel) -> None:
    kernel = Kernel(model)
    await kernel.say("Turn on the kitchen light, then play some jazz")
    reply = await kernel.say(kernel.first_callback(status="terminated", error="stopped by the user"))
    assert len(kernel.launched) == 1
    assert reply.endswith("So I did not play some jazz.")


@pytest.mark.parametrize(
    ("found", "expected"), [(True, "Done: search."), (False, "I did not find anyone, so I did not x.")]
)
async def test_the_process_reports_an_unmet_condition_as_its_output(found: bool, expected: str) -> None:
    from rosaos.events.plan import FollowUp, FollowUpLaunch, PlanStep
    from rosaos.models.process_model import LocalPlanModel

    device = FastMCP("turtlebot")

    @device.tool
    async def search(target: str = "person") -> dict[str, Any]:
        """Look for a target."""
        return {"found": found, "x": -2.5, "y": 0.5}

    lamp = Plan(steps=[PlanStep(device="lamp", tool="turn_on")], reply="Done.")
    follow_up = FollowUp(
        launches=[FollowUpLaunch(devices=["lamp"], summary="X.", plan=lamp)],
        summary="x",
        when={"found": True},
        unmet="I did not find anyone, so I did not x.",
    )
    plan = Plan(steps=[PlanStep(device="turtlebot", tool="search")], reply="Done: search.", then=follow_up)
    agent = Agent(LocalPlanModel(plan=plan), toolsets=[MCPToolset(device)])
    assert (await agent.run("Search.")).output == expected
