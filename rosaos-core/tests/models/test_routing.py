"""prefer_local: exact local matches skip the LLM; everything else goes to it."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

import pytest
from fastmcp import FastMCP
from pydantic_ai import Agent
from pydantic_ai.mcp import MCPToolset
from pydantic_ai.messages import ModelMessage, ModelResponse, TextPart
from pydantic_ai.models.function import AgentInfo, FunctionModel

from rosaos.events.types import Event, UserText
from rosaos.models.kernel_model import LocalIntentModel
from rosaos.models.process_model import LocalPlanModel
from rosaos.models.routing import KernelRouter, RoutingModel, process_model_for

from ..intents.intents_support import build_device_server, home_world


def answering_llm(text: str = "the LLM answered") -> FunctionModel:
    def answer(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        return ModelResponse(parts=[TextPart(text)])

    return FunctionModel(answer, model_name="fake-llm")


@pytest.fixture(scope="module")
def local() -> LocalIntentModel:
    return LocalIntentModel(home_world())


def said(text: str) -> Event:
    return Event(id=1, time=datetime.now(UTC), kind="user_said", source="test", payload=UserText(text=text))


def test_exact_matches_stay_local_and_the_rest_goes_to_the_llm(local: LocalIntentModel) -> None:
    llm = answering_llm()
    router = KernelRouter(local, llm, prefer_local=True)
    assert router.model_for_event(said("Turn on the kitchen light")) is local
    assert router.model_for_event(said("Turn off the light")) is llm  # ambiguous: the LLM may ask better
    assert router.model_for_event(said("What's the weather like?")) is llm
    assert router.model_for_event(said("the bedroom light")) is llm  # may answer the LLM's question


def test_prefer_local_false_sends_everything_to_the_llm(local: LocalIntentModel) -> None:
    llm = answering_llm()
    assert (
        KernelRouter(local, llm, prefer_local=False).model_for_event(said("Turn on the kitchen light")) is llm
    )


def test_without_an_llm_everything_is_local(local: LocalIntentModel) -> None:
    assert KernelRouter(local, None).model_for_event(said("What's the weather like?")) is local


def test_a_process_runs_locally_only_when_its_job_has_a_plan(local: LocalIntentModel) -> None:
    llm = answering_llm()
    [process] = local.match("Turn on the kitchen light").processes
    assert isinstance(process_model_for(process.plan, llm), LocalPlanModel)
    assert process_model_for(process.plan, llm, prefer_local=False) is llm
    assert process_model_for(None, llm) is llm
    assert isinstance(process_model_for(None, None), LocalPlanModel)


async def test_a_routing_kernel_model_launches_locally_and_leaves_the_rest_to_the_llm(
    local: LocalIntentModel,
) -> None:
    tools = FastMCP("kernel-tools")
    launched: list[list[str]] = []

    @tools.tool
    async def launch_process(
        task: str, devices: list[str], plan: dict[str, Any] | None = None
    ) -> dict[str, Any]:
        """Record the launch."""
        launched.append(devices)
        return {"process_id": len(launched)}

    agent = Agent(RoutingModel(local, answering_llm()), toolsets=[MCPToolset(tools)])
    # A bare prompt is what the user typed.
    assert (await agent.run("Turn on the kitchen light")).output == "On it: turn on the kitchen light."
    assert (await agent.run("What's the weather like?")).output == "the LLM answered"
    assert launched == [["kitchen_light"]]


async def test_a_routing_process_model_runs_the_plan_locally(local: LocalIntentModel) -> None:
    state: dict[str, Any] = {"on": False}
    [process] = local.match("Turn on the kitchen light").processes
    agent = Agent(
        RoutingModel(LocalPlanModel(plan=process.plan), answering_llm()),
        system_prompt=process.summary,
        toolsets=[MCPToolset(build_device_server("kitchen_light", state))],
    )
    assert (await agent.run(process.summary)).output == "Done: turn on the kitchen light."
    assert state["on"] is True
    assert (
        await Agent(RoutingModel(LocalPlanModel(), answering_llm())).run("Patrol.")
    ).output == "the LLM answered"
