"""What an LLM reads of a tool: its schema without the text that tells a model nothing.

Every kernel request carries the schema of every kernel tool, and every process request those of
its devices' tools. On a local 8B model each token of them costs about 0.5 ms of prefill, on
every request (``benchmarks/llm_path.py``). The tools' own schemas stay as FastMCP makes them
from the typed signatures: the MCP servers validate calls with them, and the offline engine reads
their bounds. :class:`CompactToolsModel` changes only what a model is sent:

- a parameter marked :data:`ENGINE_ONLY` (``launch_process``'s ``plan``: the offline engine's
  exact calls, 3 KB of nested schema) is left out, and so is its value in the calls of the
  history (with ``prefer_local``, the engine's launches stay in the history the LLM reads next);
  a model that sent one anyway is still validated by the server;
- an optional parameter written as ``anyOf: [X, null]`` with ``default: null`` becomes X, left
  out of ``required``: a model omits it the same way;
- ``title`` keys are dropped, and so are the length bounds of free text (``minLength: 1``, a
  ``maxLength`` of :data:`FREE_TEXT` or more): a model's sentence never comes near them, and the
  server still refuses one that does, with a message saying the limit.

Types, numeric bounds, short lengths, patterns, enums, informative defaults and descriptions stay:
they are what the tool really accepts (issue 22: a schema's maximum is the real limit).

A wrapper may also leave out whole tools a model has in another form (:data:`KERNEL_HIDDEN`); they
stay callable, for the offline engine and for a model that calls one anyway.
"""

from __future__ import annotations

import dataclasses
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any

from pydantic_ai import RunContext
from pydantic_ai.messages import ModelMessage, ModelResponse, ToolCallPart
from pydantic_ai.models import Model, ModelRequestParameters, StreamedResponse
from pydantic_ai.models.wrapper import WrapperModel
from pydantic_ai.settings import ModelSettings
from pydantic_ai.tools import ToolDefinition

ENGINE_ONLY = "x-rosaos-engine-only"
"""Schema key of a parameter only the offline engine fills in: ``Field(json_schema_extra={ENGINE_ONLY: True})``."""
KERNEL_HIDDEN = frozenset({"list_devices", "list_places"})
"""Kernel tools an LLM is not offered, since it has what they return in another form: the prompt
lists the devices with their availability (``device_state`` and ``list_processes`` say who holds
one), and ``recall`` returns the places (as does the prompt's memory summary). The offline engine
calls them; each schema was about 200 bytes of every kernel request."""
FREE_TEXT = 200
"""A string ``maxLength`` from which on the bound is not shown to a model (free text, not a code)."""


def compact_schema(schema: Any) -> Any:
    """``schema`` as a model should read it (see the module docstring); the input is not changed."""
    if isinstance(schema, list):
        return [compact_schema(item) for item in schema]
    if not isinstance(schema, dict):
        return schema
    result: dict[str, Any] = {}
    for key, value in schema.items():
        if key == "title" and isinstance(value, str):
            continue
        if key == "properties" and isinstance(value, dict):
            value = {
                name: compact_schema(prop)
                for name, prop in value.items()
                if not (isinstance(prop, dict) and prop.get(ENGINE_ONLY))
            }
        else:
            value = compact_schema(value)
        result[key] = value
    if result.get("type") == "string":
        if result.get("minLength") == 1:
            del result["minLength"]
        if isinstance(result.get("maxLength"), int) and result["maxLength"] >= FREE_TEXT:
            del result["maxLength"]
    if "required" in result and isinstance(result.get("properties"), dict):
        result["required"] = [name for name in result["required"] if name in result["properties"]]
    if isinstance(result.get("$defs"), dict):
        _drop_unused_defs(result)
    return _without_null_option(result)


def _without_null_option(schema: dict[str, Any]) -> dict[str, Any]:
    """``{anyOf: [X, {type: null}], default: null, ...}`` → ``{...X, ...}``; anything else as it is."""
    options = schema.get("anyOf")
    if not isinstance(options, list) or len(options) != 2 or schema.get("default", 0) is not None:
        return schema
    kept = [option for option in options if option != {"type": "null"}]
    if len(kept) != 1 or not isinstance(kept[0], dict):
        return schema
    merged = {key: value for key, value in schema.items() if key not in ("anyOf", "default")}
    for key, value in kept[0].items():
        merged.setdefault(key, value)
    return merged


def _drop_unused_defs(schema: dict[str, Any]) -> None:
    """Remove ``$defs`` entries nothing refers to any more (the engine-only parameter's types)."""
    defs: dict[str, Any] = schema["$defs"]
    used: set[str] = set()
    pending = [{key: value for key, value in schema.items() if key != "$defs"}]
    while pending:
        node = pending.pop()
        if isinstance(node, dict):
            ref = node.get("$ref")
            if isinstance(ref, str) and ref.startswith("#/$defs/"):
                name = ref.removeprefix("#/$defs/")
                if name not in used and name in defs:
                    used.add(name)
                    pending.append(defs[name])
            pending.extend(node.values())
        elif isinstance(node, list):
            pending.extend(node)
    kept = {name: value for name, value in defs.items() if name in used}
    if kept:
        schema["$defs"] = kept
    else:
        del schema["$defs"]


def compact_tool(tool: ToolDefinition) -> ToolDefinition:
    """``tool`` with :func:`compact_schema` applied to its parameters and its description trimmed."""
    return dataclasses.replace(
        tool,
        parameters_json_schema=compact_schema(tool.parameters_json_schema),
        description=tool.description.strip() if tool.description else tool.description,
    )


def engine_only_arguments(parameters: ModelRequestParameters) -> dict[str, frozenset[str]]:
    """Per tool, the names of its :data:`ENGINE_ONLY` parameters (from the full schemas)."""
    found: dict[str, frozenset[str]] = {}
    for tool in parameters.function_tools:
        properties = tool.parameters_json_schema.get("properties", {})
        names = frozenset(
            name for name, prop in properties.items() if isinstance(prop, dict) and prop.get(ENGINE_ONLY)
        )
        if names:
            found[tool.name] = names
    return found


def without_engine_only_arguments(
    messages: list[ModelMessage], engine_only: dict[str, frozenset[str]]
) -> list[ModelMessage]:
    """``messages`` with the engine-only arguments taken out of their tool calls (the input is not changed)."""
    if not engine_only:
        return messages
    result: list[ModelMessage] = []
    for message in messages:
        if isinstance(message, ModelResponse) and any(
            isinstance(part, ToolCallPart) and part.tool_name in engine_only for part in message.parts
        ):
            parts = [
                _without(part, engine_only[part.tool_name])
                if isinstance(part, ToolCallPart) and part.tool_name in engine_only
                else part
                for part in message.parts
            ]
            message = dataclasses.replace(message, parts=parts)
        result.append(message)
    return result


def _without(call: ToolCallPart, names: frozenset[str]) -> ToolCallPart:
    args = call.args_as_dict()
    if not names & args.keys():
        return call
    return dataclasses.replace(call, args={key: value for key, value in args.items() if key not in names})


class CompactToolsModel(WrapperModel):
    """An LLM that is sent compact tool schemas (:func:`compact_tool`); everything else passes through.

    Wrap only a model that reads schemas as text (an LLM); the offline engines read the full
    ones (their bounds clamp arguments). ``hidden`` names tools it is not offered (:data:`KERNEL_HIDDEN`).
    """

    def __init__(self, wrapped: Model | str, hidden: frozenset[str] = frozenset()) -> None:
        super().__init__(wrapped)
        self.hidden = hidden
        self._compacted: dict[str, tuple[ToolDefinition, ToolDefinition]] = {}
        """Per tool name, the last definition compacted and its compact form: the tools rarely
        change between requests, and compacting every schema again cost more than the rest of a
        no-op request (issue 26's enqueue rate). An equal definition (compared in C) reuses it."""

    def _compact(self, parameters: ModelRequestParameters) -> ModelRequestParameters:
        tools = []
        for tool in parameters.function_tools:
            if tool.name in self.hidden:
                continue
            kept = self._compacted.get(tool.name)
            if kept is None or kept[0] != tool:
                kept = self._compacted[tool.name] = (tool, compact_tool(tool))
            tools.append(kept[1])
        return dataclasses.replace(parameters, function_tools=tools)

    async def request(
        self,
        messages: list[ModelMessage],
        model_settings: ModelSettings | None,
        model_request_parameters: ModelRequestParameters,
    ) -> ModelResponse:
        messages = without_engine_only_arguments(messages, engine_only_arguments(model_request_parameters))
        return await self.wrapped.request(messages, model_settings, self._compact(model_request_parameters))

    @asynccontextmanager
    async def request_stream(
        self,
        messages: list[ModelMessage],
        model_settings: ModelSettings | None,
        model_request_parameters: ModelRequestParameters,
        run_context: RunContext[Any] | None = None,
    ) -> AsyncIterator[StreamedResponse]:
        messages = without_engine_only_arguments(messages, engine_only_arguments(model_request_parameters))
        parameters = self._compact(model_request_parameters)
        async with self.wrapped.request_stream(messages, model_settings, parameters, run_context) as stream:
            yield stream
