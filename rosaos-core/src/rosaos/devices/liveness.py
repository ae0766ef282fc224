"""Liveness of a device host: one load-proof signal per host, and a strict rule before calling it down.

A host may serve a hundred simulated instances (:mod:`rosaos.devices.host_batch`). Checking each
of them with ``get_state`` opens an MCP session per instance: on a busy two-core machine those
calls missed a 3 s timeout, every instance was declared unhealthy at once, launches were refused
and the host that serves them all was restarted, which made things worse. So liveness is split:

- **signal**: the host's heartbeat (:mod:`rosaos.devices.heartbeat`), a line its event loop writes
  every second. It needs no MCP session, no HTTP request and no token, and one beat speaks for
  every instance of that host: they share its process and its event loop, and an instance whose
  server stops ends the whole host, which the supervisor sees at once as an exit. Load delays a
  beat by one turn of the loop, not by the queue of requests.
- **verdict** (:class:`LivenessRule`): a missed beat is only late. After ``misses_allowed`` checks
  in a row found no fresh beat, one real call (``get_state`` on one instance, with a generous
  timeout) decides. The host is down only when that call fails *and* no beat came while it ran;
  until then its instances stay ``healthy`` and grantable.

A host that died is seen through its process exit, which no load can delay.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

Verdict = Literal["alive", "late", "ask"]
"""What one check means: ``alive``; ``late`` (tolerated); ``ask`` (make the real call now)."""


@dataclass
class LivenessRule:
    """Counts the probes a host missed in a row and says when a real call must decide."""

    misses_allowed: int
    """Probes in a row that may go unanswered before the real call (``unhealthy_after``)."""
    misses: int = 0

    def observe(self, answered: bool) -> Verdict:
        """Record one check (``answered``: a fresh beat came); ``ask`` once ``misses_allowed`` were missed in a row (and every time after)."""
        if answered:
            self.misses = 0
            return "alive"
        self.misses += 1
        return "ask" if self.misses >= self.misses_allowed else "late"

    def real_call_answered(self) -> None:
        """The real call answered: the host is slow, not down; start counting again."""
        self.misses = 0
