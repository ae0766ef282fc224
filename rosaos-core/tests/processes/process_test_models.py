"""Models for worker tests, imported by jobs as ``python:<this module's name>:<name>`` (``model_spec``).

Each factory returns a pydantic-ai ``FunctionModel`` that plays one scripted part: use a device,
hang, block the event loop, die, fail. Worker subprocesses import it by the
name pytest gave it (``processes_support.IMPORT_ROOT``).
"""

from __future__ import annotations

import asyncio
import json
import os
import signal
import stat
import sys
import time
from collections.abc import Awaitable

from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    ModelResponsePart,
    TextPart,
    ToolCallPart,
    ToolReturnPart,
    UserPromptPart,
)
from pydantic_ai.models.function import AgentInfo, FunctionModel


def _tool_returns(messages: list[ModelMessage]) -> list[ToolReturnPart]:
    last = messages[-1]
    return (
        [part for part in last.parts if isinstance(part, ToolReturnPart)]
        if isinstance(last, ModelRequest)
        else []
    )


def _task(messages: list[ModelMessage]) -> str:
    first = messages[0]
    assert isinstance(first, ModelRequest)
    return " ".join(str(part.content) for part in first.parts if isinstance(part, UserPromptPart))


def by_task() -> FunctionModel:
    """Plays the part its task names: "sleep", "crash", "ramp", else set every level to 42 (for manager tests)."""
    level, sleep, crash, ramp = sets_level(), sleeps(), exits(), ramps()

    async def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        task = _task(messages)
        chosen = sleep if "sleep" in task else crash if "crash" in task else ramp if "ramp" in task else level
        assert chosen.function is not None
        response = chosen.function(messages, info)
        return await response if isinstance(response, Awaitable) else response

    return FunctionModel(respond, model_name="by-task")


def ramps() -> FunctionModel:
    """Calls the ``ramp`` tool once (a long task that reports progress), then reports its result."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        returns = _tool_returns(messages)
        if returns:
            return ModelResponse(parts=[TextPart(str(returns[0].content))])
        tool = next(tool for tool in info.function_tools if tool.name.endswith("ramp"))
        return ModelResponse(parts=[ToolCallPart(tool.name, {})])

    return FunctionModel(respond, model_name="ramps")


def sets_level() -> FunctionModel:
    """Calls every ``set_level`` tool it has with level 42, then reports what the tools returned."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        returns = _tool_returns(messages)
        if returns:
            return ModelResponse(parts=[TextPart("; ".join(str(part.content) for part in returns))])
        calls: list[ModelResponsePart] = [
            ToolCallPart(tool.name, {"level": 42})
            for tool in info.function_tools
            if tool.name.endswith("set_level")
        ]
        return ModelResponse(parts=calls or [TextPart("no set_level tool")])

    return FunctionModel(respond, model_name="sets-level")


def reports_prompt() -> FunctionModel:
    """Answers with the tool names it sees and its instructions (the process system prompt), as JSON."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        report = {
            "tools": sorted(tool.name for tool in info.function_tools),
            "system": info.instructions or "",
        }
        return ModelResponse(parts=[TextPart(json.dumps(report))])

    return FunctionModel(respond, model_name="reports-prompt")


def polls_forever() -> FunctionModel:
    """Calls ``get_state`` on every request and never answers: runs into the request limit."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        tool = next(tool for tool in info.function_tools if tool.name.endswith("get_state"))
        return ModelResponse(parts=[ToolCallPart(tool.name, {})])

    return FunctionModel(respond, model_name="polls-forever")


def sleeps() -> FunctionModel:
    """Awaits forever: a process that must be stopped by its timeout or by terminate."""

    async def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        await asyncio.sleep(3600)
        raise AssertionError("unreachable")

    return FunctionModel(respond, model_name="sleeps")


def blocks() -> FunctionModel:
    """Blocks the worker's event loop: only killing the worker stops it."""

    async def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        time.sleep(3600)  # noqa: ASYNC251 - blocking on purpose: this is the stuck worker
        raise AssertionError("unreachable")

    return FunctionModel(respond, model_name="blocks")


def exits() -> FunctionModel:
    """Kills its own worker process mid-run with exit code 3."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        os._exit(3)

    return FunctionModel(respond, model_name="exits")


def fails() -> FunctionModel:
    """Raises inside the model: the process ends with status ``error``."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        raise RuntimeError("the model exploded\nsecond line that should not appear")

    return FunctionModel(respond, model_name="fails")


def reports_process() -> FunctionModel:
    """Answers with what its worker process looks like from inside, as JSON (see ``process_report``)."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        return ModelResponse(parts=[TextPart(json.dumps(process_report()))])

    return FunctionModel(respond, model_name="reports-process")


def process_report() -> dict[str, object]:
    """How the worker was started: what a job could tell apart between a spawned and a forked one."""
    import __main__

    masks = {
        line.split(":")[0]: line.split(":")[1].strip()
        for line in open("/proc/self/status").read().splitlines()  # noqa: SIM115 - /proc, in memory
        if line.startswith(("SigBlk", "SigIgn", "SigCgt"))
    }

    return {
        "argv": [os.path.basename(arg) for arg in sys.argv],
        "main": getattr(__main__.__spec__, "name", None),
        "main_file": os.path.basename(getattr(__main__, "__file__", "")),
        "own_session": os.getsid(0) == os.getpid(),
        "own_group": os.getpgid(0) == os.getpid(),
        "signals": masks,
        "sigchld": str(signal.getsignal(signal.SIGCHLD)),
        "stdio": [stat.S_IFMT(os.fstat(fd).st_mode) for fd in (0, 1, 2)],
        "environment": dict(os.environ),
        "path": sys.path,
        "cwd": os.getcwd(),
    }


def claims_done() -> FunctionModel:
    """Says the task is done without calling any tool: the model's word only."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        return ModelResponse(parts=[TextPart("Done, it is on.")])

    return FunctionModel(respond, model_name="claims-done")


def only_reads() -> FunctionModel:
    """Reads the device's state (a ``readOnlyHint`` tool), then says the change is done."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        if not _tool_returns(messages):
            return ModelResponse(parts=[ToolCallPart("get_state", {})])
        return ModelResponse(parts=[TextPart("Done, the level is 42.")])

    return FunctionModel(respond, model_name="only-reads")


def calls_unleased() -> FunctionModel:
    """Calls ``fan_set_level`` (a device it was not granted), then its own ``set_level``, then reports
    the answers it read."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        answers = [
            str(part.model_response() if hasattr(part, "model_response") else part.content)
            for message in messages
            if isinstance(message, ModelRequest)
            for part in message.parts
            if not isinstance(part, UserPromptPart)
        ]
        if len(answers) == 0:
            return ModelResponse(parts=[ToolCallPart("fan_set_level", {"level": 42})])
        if len(answers) == 1:
            return ModelResponse(parts=[ToolCallPart("set_level", {"level": 42})])
        return ModelResponse(parts=[TextPart(json.dumps(answers))])

    return FunctionModel(respond, model_name="calls-unleased")


def reports_beside_call() -> FunctionModel:
    """Calls ``set_level(42)`` with its report written beside the call, as the process prompt asks;
    if it is asked again (the call failed), it says what it read."""

    def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        if len(messages) == 1:
            return ModelResponse(
                parts=[TextPart("The level is 42."), ToolCallPart("set_level", {"level": 42})]
            )
        return ModelResponse(parts=[TextPart("asked again")])

    return FunctionModel(respond, model_name="reports-beside-call")
