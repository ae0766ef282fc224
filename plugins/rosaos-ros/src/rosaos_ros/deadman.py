"""The deadman's last line in the driver: a thread that stops the robot if the motion loop does not.

Every motion loop ends with a zero twist at its deadline (:mod:`rosaos_ros.motion`). This
watchdog covers the case where that loop cannot run on time: a blocked or overloaded event loop
in the device server. It lives in its own thread and publishes the zero twist through roslibpy,
whose sending does not need the server's loop. The motion loop arms it with the time by which
the robot must be stopped, re-arms it on every tick, and disarms it after its own zero twist.

The layer below is the robot's: a base that stops when velocity commands stop arriving (the
Create 3 after 0.5 s). It covers a dead driver process; see docs/ros.md's safety checklist.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable

log = logging.getLogger("rosaos_ros.deadman")

MARGIN = 0.1
"""Seconds past the deadline before the watchdog steps in (the bound promised is 0.2 s)."""


class DeadmanWatchdog:
    """Publishes a zero twist when an armed deadline passes by :data:`MARGIN` without a disarm."""

    def __init__(self, publish_zero: Callable[[], None], name: str = "rosaos-ros-deadman") -> None:
        self._publish_zero = publish_zero
        self._condition = threading.Condition()
        self._deadline = math.inf
        self._closed = False
        self.fired = 0
        """How many times the watchdog had to stop the robot itself (0 when the motion loop kept up)."""
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def arm(self, deadline: float) -> None:
        """The robot must be stopped by ``deadline`` (``time.monotonic()`` seconds)."""
        with self._condition:
            self._deadline = deadline
            self._condition.notify()

    def disarm(self) -> None:
        """The motion loop stopped the robot itself."""
        with self._condition:
            self._deadline = math.inf
            self._condition.notify()

    def close(self) -> None:
        """Stop the thread."""
        with self._condition:
            self._closed = True
            self._condition.notify()
        self._thread.join(timeout=2)

    def _run(self) -> None:
        with self._condition:
            while not self._closed:
                due = self._deadline + MARGIN
                now = time.monotonic()
                if now < due:
                    self._condition.wait(timeout=None if due == math.inf else due - now)
                    continue
                self._deadline = math.inf
                self.fired += 1
                log.warning("deadman: the motion loop missed its stop; publishing a zero twist")
                try:
                    self._publish_zero()
                except Exception:  # unreachable robot: its own command timeout is the last resort
                    log.exception("deadman: could not publish the zero twist")
