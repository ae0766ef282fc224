"""The worker's side of confirmations: a call that needs a person's yes waits for it.

:class:`ConfirmingToolset` wraps one device's toolset. Before a call its rule names (a tool name,
or any tool annotated ``destructiveHint`` under ``"destructive"``), it asks the kernel
(``POST /confirmations``) and waits (``GET /confirmations/{id}?wait=``). A yes runs the call; a
no, or silence until the kernel's timeout, raises :class:`ConfirmationDeclined`, which ends the
process: the kernel then releases its leases.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import httpx
from pydantic_ai import RunContext
from pydantic_ai.toolsets import ToolsetTool, WrapperToolset

from rosaos.receipts import redact, secret_args_of
from rosaos.tls import shared_context

POLL_SECONDS = 25.0

ConfirmRule = list[str] | Literal["destructive"] | None
"""What needs a yes on one device: these tool names, every destructive tool, or nothing."""
ConfirmSetting = list[str] | Literal["destructive", "off"]


def confirm_rule(
    device: ConfirmSetting | None, global_setting: ConfirmSetting | None, backend: str, on_real: bool
) -> ConfirmRule:
    """The effective rule of one device: its own setting, else the global one, else the default."""
    setting = device if device is not None else global_setting
    if setting is None:
        return "destructive" if backend == "real" and on_real else None
    if setting == "off" or setting == []:
        return None
    return setting


def needs_confirmation(rule: ConfirmRule, tool: str, annotations: dict[str, Any] | None) -> bool:
    """Whether a call of ``tool`` (with its MCP annotations) needs a yes under ``rule``."""
    if rule is None:
        return False
    if rule == "destructive":
        return bool((annotations or {}).get("destructiveHint"))
    return tool in rule


class ConfirmationDeclined(Exception):
    """A person said no (or nothing) to a call; the process ends without making it."""


@dataclass
class KernelAsker:
    """Asks the kernel at ``base_url`` on behalf of process ``process_id``."""

    base_url: str
    token: str
    process_id: int

    async def ask(self, device: str, tool: str, arguments: dict[str, Any]) -> str:
        """The final state of the question: ``yes``, ``no`` or ``expired``."""
        headers = {"Authorization": f"Bearer {self.token}"}
        body = {"process_id": self.process_id, "device": device, "tool": tool, "arguments": arguments}
        async with httpx.AsyncClient(
            base_url=self.base_url, headers=headers, timeout=POLL_SECONDS + 10, verify=shared_context()
        ) as http:
            response = await http.post("/confirmations", json=body)
            response.raise_for_status()
            item = response.json()
            while item["state"] == "pending":
                response = await http.get(f"/confirmations/{item['id']}", params={"wait": POLL_SECONDS})
                response.raise_for_status()
                item = response.json()
        return str(item["state"])


@dataclass
class ConfirmingToolset(WrapperToolset[Any]):
    """Asks before the calls ``rule`` names; passes every other call straight through."""

    device: str = ""
    rule: ConfirmRule = None
    asker: KernelAsker | None = None

    async def call_tool(
        self, name: str, tool_args: dict[str, Any], ctx: RunContext[Any], tool: ToolsetTool[Any]
    ) -> Any:
        """Wait for a yes when the rule says so, then call the tool."""
        metadata = tool.tool_def.metadata or {}
        if self.asker is not None and needs_confirmation(self.rule, name, metadata.get("annotations")):
            shown = redact(tool_args, secret_args_of(metadata.get("meta")))
            state = await self.asker.ask(self.device, name, shown)
            if state != "yes":
                why = "the person said no" if state == "no" else "nobody answered in time"
                raise ConfirmationDeclined(f"cancelled: {why} to {self.device}.{name}; nothing was done")
        return await self.wrapped.call_tool(name, tool_args, ctx, tool)
