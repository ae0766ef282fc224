"""Pushing the emergency-stop latch to every device host, and saying which could not be told.

An emergency stop latches the kernel and, through ``POST /latch``, every device host
(:mod:`rosaos.devices.latch`), local or remote. A host that does not answer is listed as *untold*
in the emergency stop's answer and on the page. While the kernel is latched it pushes the latch
again every :data:`PUSH_PERIOD` s, so a host that comes back or starts later is latched within
seconds; after a reset it pushes the reset until every host has it. Before telling any host it
writes the latch to the data directory's :data:`~rosaos.devices.latch.LATCH_FILE`, which a host
it starts there reads at its first moment.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Mapping
from pathlib import Path

import httpx

from rosaos.devices.directory import DirectoryEntry
from rosaos.devices.latch import LATCH_FILE, LATCH_PATH, LatchState, write_latch
from rosaos.processes.manager import EmergencyStop

log = logging.getLogger("rosaos.kernel.host_latch")

PUSH_PERIOD = 2.0
PUSH_TIMEOUT = 3.0


def latch_url(mcp_url: str) -> str:
    return mcp_url.rstrip("/").removesuffix("/mcp") + LATCH_PATH


def keep_latch(data_dir: Path, latch: EmergencyStop | None) -> None:
    """Write the kernel's latch for the hosts it is about to start (before any starts)."""
    state = LatchState(latched=latch is not None, reason=latch.reason[:500] if latch else "")
    write_latch(data_dir / LATCH_FILE, state)


class HostLatches:
    """Keeps every device host's latch in step with the kernel's."""

    def __init__(
        self, directory: Callable[[], Mapping[str, DirectoryEntry]], data_dir: Path | None = None
    ) -> None:
        self._directory = directory
        self._file = data_dir / LATCH_FILE if data_dir is not None else None
        self.latched = False
        self.reason = ""
        self.untold: list[str] = []
        """Hosts the last push did not reach (their instance names)."""

    async def push(self, latched: bool, reason: str = "") -> list[str]:
        """Tell every host; return (and keep) the instances whose host could not be told."""
        if self._file is not None and (latched, reason) != (self.latched, self.reason):
            write_latch(self._file, LatchState(latched=latched, reason=reason))
        self.latched, self.reason = latched, reason
        entries = list(self._directory().values())
        served = [entry for entry in entries if entry.url]
        told = await asyncio.gather(*(self._tell(entry, latched, reason) for entry in served))
        self.untold = sorted(
            [entry.name for entry, ok in zip(served, told, strict=True) if not ok]
            + [entry.name for entry in entries if not entry.url and entry.status != "not implemented"]
        )
        return self.untold

    async def run(self) -> None:
        """Push again every :data:`PUSH_PERIOD` s while latched or while a reset is still owed."""
        while True:
            await asyncio.sleep(PUSH_PERIOD)
            if self.latched or self.untold:
                try:
                    await self.push(self.latched, self.reason)
                except Exception:
                    log.exception("pushing the latch to the device hosts failed")

    async def _tell(self, entry: DirectoryEntry, latched: bool, reason: str) -> bool:
        assert entry.url is not None
        headers = {"Authorization": f"Bearer {entry.token}"} if entry.token else {}
        try:
            async with httpx.AsyncClient(timeout=PUSH_TIMEOUT) as http:
                response = await http.post(
                    latch_url(entry.url), json={"latched": latched, "reason": reason[:500]}, headers=headers
                )
        except httpx.HTTPError as error:
            log.warning("%s: could not be told the emergency stop (%s)", entry.name, error)
            return False
        if not response.is_success:
            log.warning("%s: refused the emergency stop latch: HTTP %d", entry.name, response.status_code)
        return response.is_success
