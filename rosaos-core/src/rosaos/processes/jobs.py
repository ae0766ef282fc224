"""The messages that cross process boundaries: a job sent to a worker, and the callback it posts.

Both are pydantic models because they travel as JSON: a job over the worker's stdin pipe, a
callback over HTTP to the kernel's ``POST /event``.
"""

from __future__ import annotations

from typing import Literal

from pydantic import AliasChoices, BaseModel, ConfigDict, Field

from rosaos.intents.planning.plan import Plan
from rosaos.models.select import ModelSpec
from rosaos.receipts import Receipt

ProcessStatus = Literal["ok", "error", "crashed", "timeout", "terminated", "unverified"]
"""How a process ended: ``ok`` (the agent finished, and a device call shows it), ``error`` (it
raised, or a device call failed and was not made good), ``crashed`` (the worker died), ``timeout``
(killed at the job timeout), ``terminated`` (killed on request), ``unverified`` (the model said it
was done but no device call of the process succeeded, so nothing shows it happened)."""


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
    callback_url: str
    """The kernel's ``POST /event`` URL."""
    callback_token: str
    world_devices: list[str] = Field(default_factory=list)
    """Every device of the world, so a call to one the process was not granted can be named."""


class WorkerCallback(BaseModel):
    """What a process reports when it ends; the payload of a ``worker_callback`` event."""

    model_config = ConfigDict(extra="forbid")

    process_id: int = Field(
        ge=1,
        description="The process id that launch_process returned.",
        # ``worker_id`` was this field's old name (it always held a process id): a worker or
        # script that still posts it to ``POST /event`` is understood. Deprecated: send
        # ``process_id``; events are stored and shown with ``process_id``.
        validation_alias=AliasChoices("process_id", "worker_id"),
    )
    status: ProcessStatus
    output: str | None = None
    error: str | None = None
    task: str | None = None
    plan: Plan | None = None
    """The job's plan, back to the kernel: its replies and follow-up are read as fields."""
    then: str | None = None
    """The job's follow-up for an LLM kernel, back to the kernel with the outcome."""
    model_requests: int = Field(default=0, ge=0)
    tool_calls: int = Field(default=0, ge=0)
    receipts: list[Receipt] = Field(
        default_factory=list, description="Every tool call the process made (the activity log)."
    )


def callback_idempotency_key(process_id: int) -> str:
    """The idempotency key of a process's ``worker_callback`` event.

    The worker posts its callback with this key; when it could not, the process manager enqueues
    the callback itself with the same key, so a callback that did arrive is not handled twice.
    """
    return f"process-{process_id}"
