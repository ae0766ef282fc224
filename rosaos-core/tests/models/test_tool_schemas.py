"""What an LLM is sent of a tool (issue 22): the same tool, without the text that tells it nothing."""

from __future__ import annotations

from typing import Annotated, Any

from fastmcp import Client, FastMCP
from pydantic import Field
from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    TextPart,
    ToolCallPart,
    UserPromptPart,
)
from pydantic_ai.models import ModelRequestParameters
from pydantic_ai.models.function import AgentInfo, FunctionModel
from pydantic_ai.tools import ToolDefinition

from rosaos.events.plan import Plan
from rosaos.models.tool_schemas import ENGINE_ONLY, KERNEL_HIDDEN, CompactToolsModel, compact_schema


async def schema_of(server: FastMCP, name: str) -> dict[str, Any]:
    async with Client(server) as client:
        tools = {tool.name: tool for tool in await client.list_tools()}
    return tools[name].input_schema


def server() -> FastMCP:
    mcp = FastMCP("t")

    @mcp.tool
    async def launch(
        task: Annotated[str, Field(min_length=1, max_length=4000, description="The task.")],
        then: Annotated[str | None, Field(max_length=2000, description="A next step.")] = None,
        speed: Annotated[float | None, Field(ge=0.02, le=0.3, description="m/s.")] = None,
        color: Annotated[str, Field(min_length=1, max_length=40)] = "red",
        plan: Annotated[Plan | None, Field(json_schema_extra={ENGINE_ONLY: True})] = None,
    ) -> str:
        """Launch."""
        return task

    return mcp


async def test_an_engine_only_parameter_and_its_types_are_not_shown_to_a_model() -> None:
    full = await schema_of(server(), "launch")
    assert "plan" in full["properties"] and "$defs" in full  # the server still validates a plan
    compact = compact_schema(full)
    assert "plan" not in compact["properties"]
    assert "$defs" not in compact  # Plan, PlanStep, FollowUp...: nothing else refers to them


async def test_an_optional_value_is_its_type_left_out_of_required() -> None:
    compact = compact_schema(await schema_of(server(), "launch"))
    assert compact["properties"]["then"] == {"description": "A next step.", "type": "string"}
    assert compact["properties"]["speed"] == {
        "description": "m/s.",
        "minimum": 0.02,
        "maximum": 0.3,
        "type": "number",
    }  # the real limits stay
    assert compact["required"] == ["task"]


async def test_free_text_loses_its_length_bounds_but_a_short_code_keeps_them() -> None:
    compact = compact_schema(await schema_of(server(), "launch"))
    assert compact["properties"]["task"] == {"description": "The task.", "type": "string"}
    assert compact["properties"]["color"]["maxLength"] == 40
    assert compact["properties"]["color"]["default"] == "red"  # an informative default stays


def test_the_input_schema_is_not_changed() -> None:
    schema = {
        "type": "object",
        "properties": {"a": {"anyOf": [{"type": "string"}, {"type": "null"}], "default": None}},
    }
    before = repr(schema)
    compact_schema(schema)
    assert repr(schema) == before


async def test_the_wrapped_model_is_sent_compact_tools() -> None:
    seen: list[ToolDefinition] = []

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        seen.extend(info.function_tools)
        return ModelResponse(parts=[TextPart("ok")])

    full = ToolDefinition(name="launch", parameters_json_schema=await schema_of(server(), "launch"))
    model = CompactToolsModel(FunctionModel(respond))
    await model.request([], None, ModelRequestParameters(function_tools=[full]))
    assert [tool.name for tool in seen] == ["launch"]
    assert "plan" not in seen[0].parameters_json_schema["properties"]
    assert "plan" in full.parameters_json_schema["properties"]


async def test_a_tool_whose_definition_changed_is_sent_compacted_anew() -> None:
    # The compact forms are kept between requests; a definition that changed under the same name
    # (a device added to an enum, a new description) must not be sent in its old form.
    seen: list[ToolDefinition] = []

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        seen.extend(info.function_tools)
        return ModelResponse(parts=[TextPart("ok")])

    def tool(description: str, devices: list[str]) -> ToolDefinition:
        schema = {"type": "object", "properties": {"device": {"enum": devices}}}
        return ToolDefinition(name="stop", description=description, parameters_json_schema=schema)

    model = CompactToolsModel(FunctionModel(respond))
    for definition in (tool("Stop.", ["dog"]), tool("Stop.", ["dog"]), tool("Stop now.", ["dog", "lamp"])):
        await model.request([], None, ModelRequestParameters(function_tools=[definition]))
    assert [(t.description, t.parameters_json_schema["properties"]["device"]["enum"]) for t in seen] == [
        ("Stop.", ["dog"]),
        ("Stop.", ["dog"]),
        ("Stop now.", ["dog", "lamp"]),
    ]


async def test_a_hidden_tool_is_not_offered_and_the_others_are() -> None:
    # Issue 22: list_devices and list_places say what the prompt and recall already give an LLM.
    seen: list[str] = []

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        seen.extend(tool.name for tool in info.function_tools)
        return ModelResponse(parts=[TextPart("ok")])

    tools = [
        ToolDefinition(name=name, parameters_json_schema={"type": "object", "properties": {}})
        for name in ("recall", "list_places", "list_devices", "device_state")
    ]
    model = CompactToolsModel(FunctionModel(respond), KERNEL_HIDDEN)
    await model.request([], None, ModelRequestParameters(function_tools=tools))
    assert seen == ["recall", "device_state"]


async def test_the_engines_plan_is_taken_out_of_the_history_the_model_reads() -> None:
    # With prefer_local, the offline engine's launches (with their plan) stay in the kernel's
    # history; the LLM that handles the next event is sent them without it.
    seen: list[list[ModelMessage]] = []

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        seen.append(messages)
        return ModelResponse(parts=[TextPart("ok")])

    plan = {"steps": [{"device": "lamp", "tool": "turn_on"}], "reply": "On."}
    launched = ModelResponse(
        parts=[TextPart("On it."), ToolCallPart("launch", {"task": "Turn on the lamp.", "plan": plan})]
    )
    history: list[ModelMessage] = [ModelRequest(parts=[UserPromptPart("turn on the lamp")]), launched]
    full = ToolDefinition(name="launch", parameters_json_schema=await schema_of(server(), "launch"))
    await CompactToolsModel(FunctionModel(respond)).request(
        history, None, ModelRequestParameters(function_tools=[full])
    )
    sent = seen[0][1]
    assert isinstance(sent, ModelResponse) and isinstance(sent.parts[1], ToolCallPart)
    assert sent.parts[1].args_as_dict() == {"task": "Turn on the lamp."}
    assert isinstance(launched.parts[1], ToolCallPart) and "plan" in launched.parts[1].args_as_dict()
