"""The live line on stderr while ``rosaos devices list`` or ``devices check`` waits for devices.

Shown only when stdout is a terminal (never with ``--json`` or when piped), so scripts see
exactly the output they parse. It says what is done and what each remaining check waits for::

    ⠼ Checking 6 devices: 4 done · reachy starting (4 s) · turtlebot asking (1 s)
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Iterator

from rich.console import Console
from rich.text import Text

from rosaos.devices.health import Phase


def wants_progress(json_output: bool, stderr: Console) -> bool:
    """Progress goes to a terminal user: stdout is a terminal, stderr can redraw a line, no JSON."""
    return not json_output and sys.stdout.isatty() and stderr.is_terminal


class CheckProgress:
    """What each check is doing, rendered afresh on every refresh (so the seconds tick)."""

    def __init__(self, names: list[str]) -> None:
        started = time.monotonic()
        self._phases: dict[str, tuple[Phase | None, float]] = {name: (None, started) for name in names}

    def update(self, name: str, phase: Phase) -> None:
        """Record that ``name`` entered ``phase`` now."""
        if name in self._phases:
            self._phases[name] = (phase, time.monotonic())

    def __rich__(self) -> Text:
        now = time.monotonic()
        total = len(self._phases)
        busy = [(n, p, now - t) for n, (p, t) in self._phases.items() if p != "done"]
        if total == 1 and busy:
            name, phase, seconds = busy[0]
            line = f"Checking {name}: {phase or 'checking'} ({seconds:.0f} s)"
        else:
            line = f"Checking {total} devices: {total - len(busy)} done"
            line += "".join(f" · {n} {p or 'checking'} ({s:.0f} s)" for n, p, s in busy)
        return Text(line, no_wrap=True, overflow="ellipsis")

    @contextlib.contextmanager
    def shown_on(self, console: Console) -> Iterator[None]:
        """Show the line on ``console`` for the block's duration; it disappears afterwards."""
        with console.status(self):
            yield
