"""The kernel's turn on an event the offline engine answers, without a pydantic-ai agent run.

The local-intent engine (:class:`~rosaos.models.kernel_model.LocalIntentModel`) is a pure
function of the conversation: given the messages so far it returns the next response parts.
An agent run around it costs about 8 ms of CPU per event on a 2-core machine (its graph, run
context, history preparation), ten times the engine's own match, and a command costs two events
(the sentence and its process's callback). This turn asks the engine directly and calls the
kernel's tools through the same toolset the agent would use, recording the same messages: a
request with the rendered event, the engine's response, the tool results (a refused launch is a
``failed`` result, as ``tool_error_behavior="failed"`` makes it in an agent run), and so on until
the engine answers in text. The kernel's history, its updates and what an LLM reads later are
therefore the same whichever way the turn ran. Events for an LLM still run as agent runs.

The request carries the typed event beside its rendered text
(:func:`~rosaos.models.conversation.event_request`): the engine reads the event, an LLM that
reads this history later reads the text. An engine inside a wrapper (the bench counts its
requests) is asked through the wrapper's ``request``, so the wrapper sees every request.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pydantic_ai import ModelRetry, RunContext, ToolFailed, UsageLimitExceeded
from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelRequestPart,
    ModelResponse,
    RetryInfo,
    ToolCallPart,
    ToolReturnPart,
)
from pydantic_ai.models import Model, ModelRequestParameters
from pydantic_ai.toolsets import AbstractToolset, ToolsetTool
from pydantic_ai.usage import RunUsage

from rosaos.events.types import Event
from rosaos.models.conversation import event_request
from rosaos.models.kernel_model import LocalIntentModel


@dataclass
class TurnResult:
    """What a turn added to the conversation, and the text it ended with."""

    new_messages: list[ModelMessage]
    output: str


async def offline_turn(
    model: Model,
    toolset: AbstractToolset[Any],
    event: Event,
    prompt: str,
    *,
    history: list[ModelMessage],
    instructions: str,
    request_limit: int,
) -> TurnResult:
    """Answer ``event`` with ``model`` (the engine, or a wrapper around it), calling ``toolset``'s
    tools as it asks; ``prompt`` is the event as an LLM reads it, kept in the history.

    Raises :class:`UsageLimitExceeded` after ``request_limit`` responses without a final text,
    like an agent run with that request limit.
    """
    ctx: RunContext[Any] = RunContext(deps=None, model=model, usage=RunUsage(), prompt=prompt)
    tools = await toolset.get_tools(ctx)
    names = list(tools)
    parameters = ModelRequestParameters(function_tools=[tool.tool_def for tool in tools.values()])
    new: list[ModelMessage] = [event_request(event, prompt, instructions)]
    for _ in range(request_limit):
        if isinstance(model, LocalIntentModel):  # the bare engine: no request preparation needed
            response = ModelResponse(
                parts=model.respond([*history, *new], names), model_name=model.model_name
            )
        else:
            response = await model.request([*history, *new], None, parameters)
        new.append(response)
        calls = [part for part in response.parts if isinstance(part, ToolCallPart)]
        if not calls:
            return TurnResult(new, response.text or "")
        results = [await _call(toolset, tools, call, ctx) for call in calls]
        new.append(ModelRequest(parts=results, instructions=instructions))
    raise UsageLimitExceeded(f"The next request would exceed the request_limit of {request_limit}")


async def _call(
    toolset: AbstractToolset[Any],
    tools: dict[str, ToolsetTool[Any]],
    call: ToolCallPart,
    ctx: RunContext[Any],
) -> ModelRequestPart:
    """Run one tool call; its result, a failed result, or a retried one, as an agent run records them.

    A call to be made again is the call's own return marked ``outcome="retried"`` (pydantic-ai's
    replacement for the deprecated ``RetryPromptPart``), with the cause in ``retry`` for our code.
    """
    tool = tools.get(call.tool_name)
    if tool is None:
        return ToolReturnPart(
            tool_name=call.tool_name,
            content=f"Unknown tool name: {call.tool_name!r}. Available tools: {', '.join(map(repr, tools))}",
            tool_call_id=call.tool_call_id,
            outcome="retried",
            retry=RetryInfo(cause="unknown_tool"),
        )
    ctx.tool_name, ctx.tool_call_id = call.tool_name, call.tool_call_id
    try:
        content = await toolset.call_tool(call.tool_name, call.args_as_dict(), ctx, tool)
    except ToolFailed as failed:
        return ToolReturnPart(
            tool_name=call.tool_name, content=failed.message, tool_call_id=call.tool_call_id, outcome="failed"
        )
    except ModelRetry as retry:
        return ToolReturnPart(
            tool_name=call.tool_name,
            content=retry.message,
            tool_call_id=call.tool_call_id,
            outcome="retried",
            retry=RetryInfo(cause="model_retry"),
        )
    return ToolReturnPart(tool_name=call.tool_name, content=content, tool_call_id=call.tool_call_id)
