"""Scripted pydantic-ai models for ``benchmarks/kernel.py`` (``FunctionModel``, no LLM).

The kernel runs in the benchmark's own process; the workers import this module in their
subprocess as ``python:bench_models:worker_model``, with ``benchmarks/`` on ``PYTHONPATH``.

- :func:`kernel_model` plans instantly: the user text ``bench RUN DEVICE TOOL`` becomes
  ``launch_process(task="bench RUN: call TOOL", devices=[DEVICE])`` in its first answer.
- :func:`worker_model` calls the task's tool in its first answer, and ends in its second.
- :func:`noop_model` answers every event with a short text, at once.

Both sides stamp the moments of the latency path with :func:`now` (``CLOCK_MONOTONIC``, one
clock for every process on the machine): the kernel model into :data:`KERNEL_TRACE`, the worker
model as JSON lines appended to the file named by ``ROSAOS_BENCH_TRACE``.
"""

from __future__ import annotations

import json
import os
import re
import time

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

TRACE_ENV = "ROSAOS_BENCH_TRACE"
"""The file the worker model appends its time stamps to (one JSON object a line)."""

KERNEL_TRACE: dict[int, dict[str, float]] = {}
"""Run number -> phase -> time stamp, filled by :func:`kernel_model` in the kernel's process."""

CALLBACKS: dict[int, float] = {}
"""Process id -> when the kernel model read its worker callback."""

_REQUEST = re.compile(r"bench (\d+) (\w+) (\w+)")
_TASK = re.compile(r"bench (\d+): call (\w+)")
_CALLBACK = re.compile(r"\[Process callback\] process=(\d+)")


def now() -> float:
    """``CLOCK_MONOTONIC`` in seconds: comparable between the kernel, its workers and the benchmark."""
    return time.clock_gettime(time.CLOCK_MONOTONIC)


def _user_text(messages: list[ModelMessage]) -> str:
    for message in reversed(messages):
        if isinstance(message, ModelRequest):
            for part in message.parts:
                if isinstance(part, UserPromptPart) and isinstance(part.content, str):
                    return part.content
    return ""


def _tool_results(messages: list[ModelMessage]) -> list[ToolReturnPart | RetryPromptPart]:
    last = messages[-1]
    if not isinstance(last, ModelRequest):
        return []
    return [part for part in last.parts if isinstance(part, ToolReturnPart | RetryPromptPart)]


def kernel_model() -> FunctionModel:
    """The instant planner: ``bench RUN DEVICE TOOL`` launches one process at once."""

    async def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        if _tool_results(messages):
            return ModelResponse(parts=[TextPart("launched")])
        text = _user_text(messages)
        if callback := _CALLBACK.search(text):
            CALLBACKS[int(callback.group(1))] = now()
            return ModelResponse(parts=[TextPart("done")])
        request = _REQUEST.search(text)
        if request is None:
            return ModelResponse(parts=[TextPart("ok")])
        run, device, tool = request.groups()
        KERNEL_TRACE.setdefault(int(run), {})["kernel_model"] = now()
        task = f"bench {run}: call {tool}"
        return ModelResponse(parts=[ToolCallPart("launch_process", {"task": task, "devices": [device]})])

    return FunctionModel(respond, model_name="bench-kernel")


def noop_model() -> FunctionModel:
    """A kernel that only answers: the cost of the queue and the kernel loop around the model."""

    async def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        return ModelResponse(parts=[TextPart("ok")])

    return FunctionModel(respond, model_name="bench-noop")


def _trace(run: int, phase: str) -> None:
    path = os.environ.get(TRACE_ENV)
    if not path:
        return
    line = json.dumps({"run": run, "phase": phase, "t": now(), "pid": os.getpid()}) + "\n"
    # One small O_APPEND write per line: lines from concurrent workers do not interleave.
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
    try:
        os.write(fd, line.encode())
    finally:
        os.close(fd)


def worker_model() -> FunctionModel:
    """The process agent: call the task's tool first, then report."""

    async def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        task = _TASK.search(info.instructions or "")
        if task is None:
            return ModelResponse(parts=[TextPart("no bench task in the instructions")])
        run, tool = int(task.group(1)), task.group(2)
        if _tool_results(messages):
            _trace(run, "tool_returned")
            return ModelResponse(parts=[TextPart(f"called {tool}")])
        _trace(run, "worker_model")
        return ModelResponse(parts=[ToolCallPart(tool, {})])

    return FunctionModel(respond, model_name="bench-worker")
