"""What a worker tells the pool over its stdout pipe: one typed message per JSON line.

The pool writes a :class:`~rosaos.processes.jobs.WorkerJob` line to the worker's stdin; the worker
answers with these. The pipe is the only route a process's end takes to the kernel: the pool runs
in the kernel's process, so a second route (HTTP) would add no durability, only a race.

- :class:`Ready`: the imports are done; the worker takes jobs.
- :class:`Progress`: a device tool of the running job sent an MCP progress notification.
- :class:`Done`: the job ended; ``callback`` says how.
- :class:`Rejected`: the line the pool sent is not a valid job.

A worker that dies mid-job sends nothing: the pool's watcher reports that end
(:mod:`rosaos.processes.watcher`).
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter

from rosaos.processes.jobs import WorkerCallback


class _Message(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Ready(_Message):
    """The worker finished its imports and waits for a job."""

    event: Literal["ready"] = "ready"
    pid: int


class Progress(_Message):
    """A running job's device tool reported progress (a long task such as a robot's search)."""

    event: Literal["progress"] = "progress"
    process_id: int = Field(ge=1)
    device: str
    progress: float
    total: float | None = None
    message: str = Field(default="", max_length=500)


class Done(_Message):
    """The job ended (ok or not): the process's one and only end."""

    event: Literal["done"] = "done"
    process_id: int = Field(ge=1)
    callback: WorkerCallback


class Rejected(_Message):
    """The pool sent a line that is not a valid job; the worker stays ready for the next."""

    event: Literal["rejected"] = "rejected"
    error: str


WorkerMessage = Annotated[Ready | Progress | Done | Rejected, Field(discriminator="event")]
"""One line a worker writes to the pool, told apart by ``event``."""

WORKER_MESSAGE: TypeAdapter[WorkerMessage] = TypeAdapter(WorkerMessage)


def encode(message: Ready | Progress | Done | Rejected) -> str:
    """``message`` as one protocol line (newline included)."""
    return message.model_dump_json() + "\n"
