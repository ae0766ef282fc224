"""What a process agent's device calls really did, seen by the worker rather than told by the model.

Device errors go back to the model as failed tool results (so it can read them and adapt), and a
model then often writes a polite sentence ("Sorry, I couldn't drive: Connection closed"). The
worker must not report that as success. Every granted device's toolset is wrapped in an
:class:`ObservedToolset`, which notes each call and how it ended in the job's :class:`ToolCallLog`;
a failure that no later success of the same tool on the same device made good ends the process
in ``error``, with the device's own message.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

from pydantic_ai import RunContext
from pydantic_ai.toolsets import AbstractToolset, ToolsetTool, WrapperToolset


@dataclass(frozen=True)
class ToolCall:
    """One call a process made to one device's tool."""

    device: str
    tool: str
    ok: bool
    error: str | None
    seconds: float
    changes: bool = True
    """False for a tool annotated ``readOnlyHint``: its success shows nothing changed (processes/outcome.py)."""


@dataclass
class ToolCallLog:
    """Every device call of one job, in order."""

    calls: list[ToolCall] = field(default_factory=list)

    def unresolved_failure(self) -> ToolCall | None:
        """The last failed call that no later success of the same tool on the same device followed."""
        failure = None
        for call in self.calls:
            if not call.ok:
                failure = call
            elif failure is not None and (call.device, call.tool) == (failure.device, failure.tool):
                failure = None
        return failure


@dataclass
class ObservedToolset(WrapperToolset[Any]):
    """A device's toolset that records each call and its outcome in ``log``; behaviour unchanged."""

    device: str = ""
    log: ToolCallLog = field(default_factory=ToolCallLog)

    async def call_tool(
        self, name: str, tool_args: dict[str, Any], ctx: RunContext[Any], tool: ToolsetTool[Any]
    ) -> Any:
        started = time.monotonic()
        changes = not read_only(tool)
        try:
            result = await self.wrapped.call_tool(name, tool_args, ctx, tool)
        except Exception as failure:  # ToolFailed, ModelRetry, a lost connection: all are failures
            message = getattr(failure, "message", None) or str(failure) or type(failure).__name__
            self.log.calls.append(
                ToolCall(self.device, name, False, message, time.monotonic() - started, changes)
            )
            raise
        self.log.calls.append(ToolCall(self.device, name, True, None, time.monotonic() - started, changes))
        return result


def read_only(tool: ToolsetTool[Any]) -> bool:
    """Whether the MCP server annotated ``tool`` ``readOnlyHint: true`` (unannotated: it may change things)."""
    annotations = (tool.tool_def.metadata or {}).get("annotations") or {}
    return annotations.get("readOnlyHint") is True


def observed(toolset: AbstractToolset[Any], device: str, log: ToolCallLog) -> ObservedToolset:
    """``toolset`` with its calls recorded in ``log`` under ``device``."""
    return ObservedToolset(wrapped=toolset, device=device, log=log)
