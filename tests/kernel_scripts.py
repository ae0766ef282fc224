"""Scripted pydantic-ai models for end-to-end kernel tests (``FunctionModel``, no LLM).

Workers import this module in their own subprocess as ``python:kernel_scripts:<factory>``, with
this folder on ``PYTHONPATH``.

Kernel script: user text ``DEVICES: TASK; DEVICES: TASK`` launches one process per clause
(``kitchen_light,living_room_lamp: call turn_off {}``); ``slow SECONDS`` sleeps and answers;
``turn on the kitchen light`` is the one natural sentence it knows. ``stop`` or ``stop: DEVICES``
calls the ``stop`` tool; ``state DEVICE`` calls ``device_state``. A worker callback gets the
reply ``process N: STATUS``. Timers, as an LLM would use the tools: ``timer SECONDS: DEVICES:
TASK`` calls ``set_timer`` with the rest as its action, ``list timers`` and ``cancel timer``
call ``list_timers`` and ``cancel_timer``; a ``[Timer fired]`` event runs its action line as above.
A sentence that is itself a worker script (``call turn_on {}``) launches a kitchen_light process
with no task, as a model may when the user's sentence is the whole task.

Worker script (the task): lines ``call TOOL {json args}``, ``sleep SECONDS``, run in order.
"""

from __future__ import annotations

import asyncio
import json

from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    RetryPromptPart,
    TextPart,
    ToolCallPart,
    ToolReturnPart,
    UserPromptPart,
)
from pydantic_ai.models.function import AgentInfo, FunctionModel

SENTENCES = {"turn on the kitchen light": "kitchen_light: call turn_on {}"}

KERNEL_TOOLS_SEEN: set[str] = set()
"""Every tool name the scripted kernel was offered (tests check it never sees a device tool)."""


def _user_text(messages: list[ModelMessage]) -> str:
    for message in reversed(messages):
        if isinstance(message, ModelRequest):
            for part in message.parts:
                if isinstance(part, UserPromptPart) and isinstance(part.content, str):
                    return part.content
    return ""


def kernel_model() -> FunctionModel:
    """The scripted kernel."""

    async def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        KERNEL_TOOLS_SEEN.update(tool.name for tool in info.function_tools)
        last = messages[-1]
        assert isinstance(last, ModelRequest)
        results = [p for p in last.parts if isinstance(p, ToolReturnPart | RetryPromptPart)]
        if results:
            said = []
            for part in results:
                if isinstance(part, ToolReturnPart) and part.outcome == "success":
                    said.append(f"launched {part.content}")
                elif isinstance(part, ToolReturnPart):
                    said.append(f"refused: {part.model_response_str()}")
                else:
                    said.append(f"refused: {part.model_response()}")
            return ModelResponse(parts=[TextPart("; ".join(said))])
        text = _user_text(messages)
        tag, _, body = text.partition("] ")
        if tag == "[Process callback":
            head = body.splitlines()[0]
            fields = dict(item.split("=", 1) for item in head.split() if "=" in item)
            return ModelResponse(parts=[TextPart(f"process {fields['process']}: {fields['status']}")])
        if tag == "[Timer fired":
            body = body.split("\naction: ", 1)[1]
        if body.startswith("timer "):
            seconds, _, action = body.removeprefix("timer ").partition(": ")
            return ModelResponse(
                parts=[ToolCallPart("set_timer", {"action": action, "in_seconds": float(seconds)})]
            )
        if body.strip() in ("list timers", "cancel timer"):
            return ModelResponse(parts=[ToolCallPart(body.strip().replace(" ", "_"), {})])
        if body.startswith("stop"):  # "stop" or "stop: dog, spotify": the lease-free stop tool
            # The first line only: a callback of the process a stop at intake ended may share the turn.
            line = body.splitlines()[0]
            names = [name.strip() for name in line.partition(":")[2].split(",") if name.strip()]
            return ModelResponse(parts=[ToolCallPart("stop", {"devices": names})])
        if body.startswith("state "):  # "state turtlebot": the read-only device_state tool
            return ModelResponse(parts=[ToolCallPart("device_state", {"device": body.split()[1]})])
        body = SENTENCES.get(body.strip().lower(), body)
        if body.startswith("slow "):
            await asyncio.sleep(float(body.split()[1]))
            return ModelResponse(parts=[TextPart(f"handled {body}")])
        if body.startswith("call "):  # the sentence is the whole task: launch_process without one
            return ModelResponse(parts=[ToolCallPart("launch_process", {"devices": ["kitchen_light"]})])
        calls = []
        for clause in body.split(";"):
            devices, _, task = clause.partition(":")
            if not task:
                return ModelResponse(parts=[TextPart(f"I don't understand {body!r}")])
            names = [d.strip() for d in devices.split(",") if d.strip()]
            calls.append(ToolCallPart("launch_process", {"task": task.strip(), "devices": names}))
        return ModelResponse(parts=calls)

    return FunctionModel(respond, model_name="scripted-kernel")


def _task(info: AgentInfo) -> list[str]:
    instructions = info.instructions or ""
    _, _, after = instructions.partition("# Your task\n")
    task, _, _ = after.partition("\n\n#")
    return [line.strip() for line in task.strip().splitlines() if line.strip()]


def _tool(info: AgentInfo, name: str) -> str:
    for tool in info.function_tools:
        if tool.name == name or tool.name.endswith(f"_{name}"):
            return tool.name
    raise AssertionError(f"no tool {name!r} among {[t.name for t in info.function_tools]}")


def worker_model() -> FunctionModel:
    """The scripted process agent."""

    async def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        steps = _task(info)
        done = sum(
            1
            for m in messages
            if isinstance(m, ModelRequest)
            for p in m.parts
            if isinstance(p, ToolReturnPart)
        )
        calls_seen = 0
        for step in steps:
            verb, _, rest = step.partition(" ")
            if verb == "sleep":
                if calls_seen == done:
                    await asyncio.sleep(float(rest))
                continue
            if verb == "call":
                if calls_seen == done:
                    name, _, args = rest.partition(" ")
                    return ModelResponse(parts=[ToolCallPart(_tool(info, name), json.loads(args or "{}"))])
                calls_seen += 1
        return ModelResponse(parts=[TextPart(f"done {done} calls")])

    return FunctionModel(respond, model_name="scripted-worker")
