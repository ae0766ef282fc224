"""The "Tools:" list of a device's prompt section, written from the device's own MCP metadata.

A driver used to describe each tool four times: the backend method, the tool's docstring in
``server.py``, its intents, and a hand-written list in ``prompt.md`` that drifted from the others.
The list is now made here, from what the device's server says when a process connects
(``tools/list``: name, parameters, description), so it names exactly the tools the process is
offered, with their real parameters; ``prompt.md`` keeps what no schema says (when to prefer
which tool, what "a bit" means).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from pydantic import BaseModel, ConfigDict, Field

MAX_DESCRIPTION = 400
"""Characters of a tool's description in the list: its first paragraph, cut here if longer."""


class ToolSummary(BaseModel):
    """What the list shows of one MCP tool: its name, parameters and the first paragraph of its description."""

    model_config = ConfigDict(frozen=True)

    name: str
    parameters: tuple[str, ...] = ()
    """Parameter names in schema order; an optional one ends in ``?``."""
    summary: str = ""

    @classmethod
    def of(cls, name: str, description: str | None, input_schema: Mapping[str, Any] | None) -> ToolSummary:
        """From the fields of an MCP ``Tool`` (``name``, ``description``, ``inputSchema``)."""
        schema = input_schema or {}
        required = set(schema.get("required", ()))
        properties = schema.get("properties", {}) or {}
        parameters = tuple(key if key in required else f"{key}?" for key in properties)
        return cls(name=name, parameters=parameters, summary=first_paragraph(description or ""))

    def line(self) -> str:
        """``- `set_brightness(brightness)`: Set the brightness in percent ...``"""
        call = f"{self.name}({', '.join(self.parameters)})" if self.parameters else self.name
        return f"- `{call}`: {self.summary}" if self.summary else f"- `{call}`"


class DeviceTools(BaseModel):
    """The tools one device's server listed, in its order."""

    model_config = ConfigDict(frozen=True)

    tools: tuple[ToolSummary, ...] = Field(default_factory=tuple)

    @classmethod
    def from_mcp(cls, tools: Sequence[Any]) -> DeviceTools:
        """From ``Client.list_tools()``: MCP ``Tool`` objects."""
        return cls(tools=tuple(ToolSummary.of(t.name, t.description, t.input_schema) for t in tools))

    def render(self, offered: Sequence[str] | None = None) -> str:
        """The "Tools:" list of the prompt section; only ``offered`` tools when given. Empty: no tools."""
        allowed = None if offered is None else frozenset(offered)
        lines = [tool.line() for tool in self.tools if allowed is None or tool.name in allowed]
        return "Tools:\n" + "\n".join(lines) if lines else ""


def first_paragraph(description: str) -> str:
    """The description up to its first blank line, on one line, cut at :data:`MAX_DESCRIPTION`."""
    paragraph = description.strip().split("\n\n", 1)[0]
    text = " ".join(paragraph.split())
    return text if len(text) <= MAX_DESCRIPTION else text[: MAX_DESCRIPTION - 1].rstrip() + "…"
