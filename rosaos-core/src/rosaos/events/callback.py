"""How a process ended, as the kernel reads it: the payload of a ``worker_callback`` event.

It carries the job's plan and follow-up back (typed), so the kernel, and the offline engine in
particular, reads them as fields. A low-layer type: the events, the processes, the engine and the
kernel all use it.
"""

from __future__ import annotations

from typing import Literal

from pydantic import AliasChoices, BaseModel, ConfigDict, Field

from rosaos.events.plan import Plan
from rosaos.receipts import Receipt

ProcessStatus = Literal["ok", "error", "crashed", "timeout", "terminated", "unverified"]
"""How a process ended: ``ok`` (the agent finished, and a device call shows it), ``error`` (it
raised, or a device call failed and was not made good), ``crashed`` (the worker died), ``timeout``
(killed at the job timeout), ``terminated`` (killed on request), ``unverified`` (the model said it
was done but no device call of the process succeeded, so nothing shows it happened)."""


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
