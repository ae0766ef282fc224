"""The worker's recorder of tool calls: one :class:`~rosaos.receipts.Receipt` per call.

:class:`RecordingToolset` wraps one device's MCP toolset (before any name prefix, so receipts
name the device's own tools), times each call, keeps the redacted arguments, the result or the
error, and the safety decision the driver reported, then passes the outcome on unchanged.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

from pydantic_ai import RunContext
from pydantic_ai.toolsets import ToolsetTool, WrapperToolset

from rosaos.receipts import Receipt, error_text, redact, result_text, safety_of, secret_args_of


@dataclass
class RecordingToolset(WrapperToolset[Any]):
    """Records every call of the wrapped device toolset into ``receipts``."""

    device: str = ""
    receipts: list[Receipt] = field(default_factory=list)

    async def call_tool(
        self, name: str, tool_args: dict[str, Any], ctx: RunContext[Any], tool: ToolsetTool[Any]
    ) -> Any:
        """Call the tool and append its receipt, whether it succeeded or failed."""
        started, clock = time.time(), time.monotonic()
        secret = secret_args_of((tool.tool_def.metadata or {}).get("meta"))
        arguments = redact(tool_args, secret)
        try:
            result = await self.wrapped.call_tool(name, tool_args, ctx, tool)
        except Exception as failure:
            error = error_text(str(getattr(failure, "message", "") or failure)) or type(failure).__name__
            self.receipts.append(
                Receipt(
                    device=self.device,
                    tool=name,
                    arguments=arguments,
                    ok=False,
                    error=error,
                    started=started,
                    duration=round(time.monotonic() - clock, 4),
                    safety=safety_of(None, error),
                )
            )
            raise
        self.receipts.append(
            Receipt(
                device=self.device,
                tool=name,
                arguments=arguments,
                ok=True,
                result=result_text(result),
                started=started,
                duration=round(time.monotonic() - clock, 4),
                safety=safety_of(result, None),
            )
        )
        return result
