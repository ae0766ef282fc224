"""Liveness of a device host: one cheap probe per host, and a strict rule before calling it down.

A host may serve a hundred simulated instances (:mod:`rosaos.devices.host_batch`). Checking each
of them with ``get_state`` opens an MCP session per instance: on a busy two-core machine those
calls miss a 3 s timeout, every instance is declared unhealthy at once, launches are refused and
the host that serves them all is restarted, which makes things worse. So liveness is split:

- **probe**: ``GET /health`` on one of the host's ports, over a kept-open connection. It needs no
  MCP session and no token, and one answer speaks for every instance of that host, because they
  share the process and its event loop (an instance whose server stops ends the whole host,
  which the supervisor sees at once as an exit).
- **verdict** (:class:`LivenessRule`): a late probe is only late. After ``misses_allowed`` probes
  in a row went unanswered, one real call (``get_state`` on one instance, with a generous
  timeout) decides. The host is down only when that fails too; until then its instances stay
  ``healthy`` and grantable.

A host that died is seen through its process exit, which no load can delay.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import httpx

from rosaos.devices.serve import HEALTH_PATH, MCP_PATH

Verdict = Literal["alive", "late", "ask"]
"""What one probe result means: ``alive``; ``late`` (tolerated); ``ask`` (make the real call now)."""


def health_url(mcp_url: str) -> str:
    """The open ``/health`` URL of the server whose MCP URL is ``mcp_url``."""
    base = mcp_url.rstrip("/")
    if base.endswith(MCP_PATH):
        base = base[: -len(MCP_PATH)]
    return base + HEALTH_PATH


async def probe(client: httpx.AsyncClient, mcp_url: str, timeout: float) -> bool:
    """One liveness probe: True when the host answered ``/health`` with 200 within ``timeout``."""
    try:
        response = await client.get(health_url(mcp_url), timeout=timeout)
    except httpx.HTTPError:
        return False
    return response.status_code == 200


@dataclass
class LivenessRule:
    """Counts the probes a host missed in a row and says when a real call must decide."""

    misses_allowed: int
    """Probes in a row that may go unanswered before the real call (``unhealthy_after``)."""
    misses: int = 0

    def observe(self, answered: bool) -> Verdict:
        """Record one probe; ``ask`` once ``misses_allowed`` were missed in a row (and every time after)."""
        if answered:
            self.misses = 0
            return "alive"
        self.misses += 1
        return "ask" if self.misses >= self.misses_allowed else "late"

    def real_call_answered(self) -> None:
        """The real call answered: the host is slow, not down; start counting again."""
        self.misses = 0
