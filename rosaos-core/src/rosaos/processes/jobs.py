"""The messages that cross process boundaries: a job sent to a worker, and the callback it ends with.

Both are pydantic models because they travel as JSON over the worker's pipes: a job on its stdin,
the callback inside the ``done`` message on its stdout (:mod:`rosaos.processes.protocol`). The
callback's type lives in the low layer (:mod:`rosaos.events.callback`), as an event payload; it is
re-exported here beside the job.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from rosaos.events.callback import ProcessStatus, WorkerCallback, callback_idempotency_key
from rosaos.events.plan import Plan
from rosaos.models.select import ModelSpec

__all__ = [
    "GrantedDevice",
    "ProcessStatus",
    "WorkerCallback",
    "WorkerJob",
    "callback_idempotency_key",
]


class GrantedDevice(BaseModel):
    """A device a process may use: where its MCP server is, and what the agent should know about it."""

    model_config = ConfigDict(extra="forbid")

    name: str
    driver: str
    url: str
    token: str
    description: str
    prompt: str
    confirm: list[str] | Literal["destructive"] | None = None
    """Tools that need a person's yes first (names, or every destructive one)."""
    tools: list[str] | None = None
    """The only tools of this device the process is offered; None: all of them. An always-attached
    device the kernel did not ask for comes with its speaking tools only."""
    on_request_tools: list[str] = Field(default_factory=list)
    """Tools a process model is offered only when its task asks for them (:mod:`rosaos.processes.tool_offer`)."""
    on_request_pattern: str | None = None
    """The words by which a task asks for them (a case-insensitive regular expression)."""
    server_epoch: str | None = None
    """Names the server process serving the device now, as the kernel knows it: a worker's kept
    session with the same epoch needs no check before the job; None (a remote device): check it."""


class WorkerJob(BaseModel):
    """One task for one process agent. Sent to an idle worker as one JSON line."""

    model_config = ConfigDict(extra="forbid")

    process_id: int = Field(ge=1)
    task: str = Field(min_length=1)
    plan: Plan | None = None
    """The offline engine's exact tool calls, when it planned the task: the worker runs them
    without a model (an LLM running the process reads them rendered, in its prompt)."""
    then: str | None = None
    """An LLM kernel's follow-up (``launch_process(..., then=...)``): not this process's to do."""
    devices: list[GrantedDevice]
    model: ModelSpec
    base_prompt: str
    timeout: float = Field(gt=0)
    request_limit: int = Field(ge=1)
    kernel_url: str
    """The kernel API's base URL, where the worker asks a person to confirm a tool call."""
    kernel_token: str
    world_devices: list[str] = Field(default_factory=list)
    """Every device of the world, so a call to one the process was not granted can be named."""
