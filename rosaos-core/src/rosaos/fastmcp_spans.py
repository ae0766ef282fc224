"""FastMCP's own OpenTelemetry spans, off in rosaOS's processes unless the user asks for them.

FastMCP opens a span for every MCP request it serves or sends (``native`` mode, its default),
building the span's attributes (method, server, session, auth) and attaching an OpenTelemetry
context each time. rosaOS configures no OpenTelemetry SDK, so those spans go nowhere; on the
offline command's path they were about a twentieth of a device host's Python calls per tool call
(3,454 → 3,276 per ``turn_on`` or ``turn_off`` of the Tapo sim), and the kernel's in-process tool
calls and the worker's device calls paid their share too (issue 26, part 8).

:func:`spans_off` turns them off (``off``: FastMCP opens no span and propagates no trace context)
where rosaOS starts FastMCP: the kernel, each worker, each device host. Someone who wires up an
OpenTelemetry exporter says so with ``FASTMCP_TELEMETRY_MODE`` (``native`` or
``propagation_only``), and that choice is kept.
"""

from __future__ import annotations

import os

import fastmcp

ENV = "FASTMCP_TELEMETRY_MODE"
"""FastMCP's own setting; when set, rosaOS leaves the mode to it."""


def spans_off() -> None:
    """Turn FastMCP's spans off in this process, unless :data:`ENV` chose a mode."""
    if not os.environ.get(ENV):
        fastmcp.settings.telemetry_mode = "off"
