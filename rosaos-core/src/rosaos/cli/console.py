"""The console every command prints through: rich on a terminal, no wrapping when piped."""

from __future__ import annotations

import sys

from rich.console import Console

PIPED_WIDTH = 200
"""Piped output (logs, scripts, CI) is not cut to 80 columns: a URL or table row stays whole."""


def console(stderr: bool = False) -> Console:
    """A console for command output on stdout (or stderr)."""
    stream = sys.stderr if stderr else sys.stdout
    width = None if stream.isatty() else PIPED_WIDTH
    return Console(stderr=stderr, highlight=False, width=width, soft_wrap=not stream.isatty())
