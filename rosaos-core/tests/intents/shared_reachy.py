"""One simulated Reachy Mini daemon lent to every Reachy task of the bench-task tests.

Each Reachy task runs its plan on a fresh ``reachy`` sim backend, as ``rosaos bench`` does. The
backend's own daemon (MuJoCo) took about 5 s of each such task's 8 to start and stop, for 20
tasks. :func:`lent_daemon` starts that daemon once and has every backend connect to it instead:

- the backend is still new for every task: a new SDK connection, companion, speaker and motion
  controller, and it takes up the task's initial state as always (motors on, then head, antennas
  and body moved to it);
- what it cannot reset is the one thing only a fresh daemon shows, the sleep pose of a robot that
  starts asleep, so a task whose Reachy starts asleep gets a daemon of its own (none does today);
- the daemon runs on an event loop and thread of its own (each test has its own loop), which
  pings its watchdog; closing a backend leaves it running, and the fixture stops it at the end.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
from collections.abc import Coroutine, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import pytest

T = TypeVar("T")


@dataclass
class _Lent:
    """What a backend sees of the shared daemon; closing the backend does not stop it."""

    mode: str
    port: int
    fallback_reason: str | None

    async def stop(self) -> None:
        """The fixture stops the daemon, after the last task."""


@contextlib.contextmanager
def lent_daemon(log_dir: Path) -> Iterator[None]:
    """Start one simulated daemon and have every ``reachy`` sim backend use it until exit."""
    from rosaos_reachy.daemon import SimDaemon

    # The daemon lives on a loop and thread of its own, for as long as the fixture: its watchdog
    # pinger runs there, and the daemon dies with the thread that started it (PR_SET_PDEATHSIG).
    loop = asyncio.new_event_loop()
    thread = threading.Thread(target=loop.run_forever, name="shared reachy daemon", daemon=True)
    thread.start()

    def on_its_loop(work: Coroutine[Any, Any, T]) -> T:
        return asyncio.run_coroutine_threadsafe(work, loop).result()

    try:
        daemon = on_its_loop(SimDaemon.start("auto", log_dir, 90.0))
        lent = _Lent(daemon.mode, daemon.port, daemon.fallback_reason)

        async def borrow(wanted: str, _log_dir: Path, _timeout: float) -> _Lent:
            assert wanted in ("auto", daemon.mode), f"this task wants sim physics {wanted!r}"
            return lent

        try:
            with pytest.MonkeyPatch.context() as patch:
                patch.setattr(SimDaemon, "start", staticmethod(borrow))
                yield
        finally:
            on_its_loop(daemon.stop())
    finally:
        loop.call_soon_threadsafe(loop.stop)
        thread.join()
        loop.close()


def starts_awake(sim: Mapping[str, Any]) -> bool:
    """Whether a Reachy task starts awake (the shared daemon cannot show the sleep pose)."""
    return bool(sim.get("awake", True))
