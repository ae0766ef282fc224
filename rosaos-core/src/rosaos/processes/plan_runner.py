"""Runs an offline plan's device calls directly, without a pydantic-ai agent run.

A task the kernel's local-intent engine planned needs no model: its ``rosaos-plan`` says which
tools to call with which arguments, and how to word the reply. Run through an agent, each step
is a model request to :class:`~rosaos.models.process_model.LocalPlanModel` that hands back the
next call, plus the agent graph around it: on a 2-core machine that is about 13 ms of a warm
worker's 25 ms before the device is even called, with the kernel's own work competing for the
CPU. This runner makes the same calls through the same toolsets (confirmation, receipts, the call
log) and words the same reply with the same functions, so a planned process behaves exactly as
before, only sooner. Anything else (an LLM model, a task without a plan) still runs as an agent.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from pydantic_ai import RunContext
from pydantic_ai.models import Model
from pydantic_ai.toolsets import AbstractToolset, ToolsetTool
from pydantic_ai.usage import RunUsage

from rosaos.confirmations.confirming import ConfirmationDeclined
from rosaos.events.plan import Plan
from rosaos.intents.grammar.phrases import phrase
from rosaos.models.conversation import content_text
from rosaos.models.process_model import clamp_arguments, plan_reply, resolve_tool


async def run_plan(plan: Plan, toolsets: Sequence[AbstractToolset[Any]], model: Model, language: str) -> str:
    """Call ``plan``'s steps in order on ``toolsets``; the reply the plan model would have given.

    Stops at the first failed step, with the plan's failure sentence naming the device's error.
    """
    ctx: RunContext[Any] = RunContext(deps=None, model=model, usage=RunUsage())
    # Called through the toolset that listed it (its wrappers ask for confirmation, write the
    # receipt and log the call); ``tool.toolset`` would be the bare MCP session underneath.
    tools: dict[str, tuple[AbstractToolset[Any], ToolsetTool[Any]]] = {}
    for toolset in toolsets:
        tools.update({name: (toolset, tool) for name, tool in (await toolset.get_tools(ctx)).items()})
    results: list[Any] = []
    for step in plan.steps:
        name = resolve_tool(step.device, step.tool, list(tools))
        if name is None:
            reason = phrase(language, "no_tool", tool=step.tool, device=step.device, tools=", ".join(tools))
            return plan.failure.replace("{error}", reason)
        toolset, tool = tools[name]
        arguments = clamp_arguments(step.args, tool.tool_def)
        ctx.tool_name, ctx.tool_call_id = name, f"plan-{len(results) + 1}"
        try:
            result = await toolset.call_tool(name, arguments, ctx, tool)
        except ConfirmationDeclined:
            raise  # a person said no: the process ends "terminated", as from an agent run
        except Exception as failure:  # a device error, a lost session: the plan's failure sentence
            message = getattr(failure, "message", None) or str(failure) or type(failure).__name__
            return plan.failure.replace("{error}", content_text(message))
        results.append(result)
    if not results:
        return plan.reply
    return plan_reply(plan, results)
