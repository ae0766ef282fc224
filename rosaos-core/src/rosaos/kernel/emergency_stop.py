"""The latched emergency stop: every process terminated, every device safe-stopped, until a person resets it.

The latch lives in the process manager (it refuses every launch while latched), in the event
store (so a restart is latched too) and on every device host (:mod:`rosaos.kernel.host_latch`).
"""

from __future__ import annotations

import asyncio
import json
import logging
import sqlite3
from collections.abc import Awaitable, Callable
from datetime import UTC, datetime

from pydantic import ValidationError

from rosaos.devices.supervisor import SafeStopOutcome
from rosaos.kernel.api.schemas import DeviceSafeStop, EmergencyStopReport, EmergencyStopState
from rosaos.kernel.database import StoreClosedError
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.host_latch import HostLatches
from rosaos.kernel.pending_stops import PendingStops
from rosaos.kernel.updates import UpdateStream
from rosaos.processes.manager import EmergencyStop, ProcessManager

log = logging.getLogger(__name__)

EMERGENCY_STOP_KEY = "emergency_stop"
"""The event store's key for the latched emergency stop (``EmergencyStop`` as JSON, or null)."""


class EmergencyStopControl:
    """Latches, reports and resets the emergency stop (the ``/estop`` routes and ``rosaos estop``)."""

    def __init__(
        self,
        manager: ProcessManager,
        safe_stop_all: Callable[[], Awaitable[list[SafeStopOutcome]]],
        store: EventStore,
        updates: UpdateStream,
        host_latches: HostLatches,
        pending_stops: PendingStops,
    ) -> None:
        self._manager = manager
        self._safe_stop_all = safe_stop_all
        self._store = store
        self._updates = updates
        self._host_latches = host_latches
        self._pending_stops = pending_stops

    async def stop(self, reason: str) -> EmergencyStopReport:
        """Terminate every process, call every device's safe_stop, and latch until reset.

        The latch is in memory at once, and saved in the event store while the devices stop: the
        stop never waits on the disk, and the answer comes once the latch survives a restart.
        """
        stopped = await self._manager.latch_emergency_stop(reason)
        latch = self._manager.emergency_stop
        assert latch is not None
        outcomes, saved, untold = await asyncio.gather(
            self._safe_stop_all(), self._save(latch), self._host_latches.push(True, reason)
        )
        await self._pending_stops.note(outcomes)  # an unreachable device is stopped when it is back
        report = EmergencyStopReport(
            latched=True,
            reason=latch.reason,
            time=latch.time,
            terminated=[info.id for info in stopped],
            devices=[DeviceSafeStop(name=o.instance, ok=o.ok, detail=o.detail) for o in outcomes],
            saved=saved,
            untold_hosts=untold,
        )
        await self._updates.publish("error", f"EMERGENCY STOP: {reason}", report.model_dump(mode="json"))
        return report

    async def reset(self) -> EmergencyStopState:
        """Unlatch the emergency stop (a person decided it is safe).

        The latch is cleared on disk first: if that fails, the stop stays latched and this raises.
        """
        latch = self._manager.emergency_stop
        if latch is None:  # nothing to reset: say nothing on the updates stream
            return self.state()
        await self._store.set_value(EMERGENCY_STOP_KEY, None)
        if self._manager.emergency_stop is latch:  # not if a new stop came while the disk was busy
            self._manager.reset_emergency_stop()
            await self._host_latches.push(False)
            await self._updates.publish("notice", "emergency stop reset: processes may run again", {})
        return self.state()

    def state(self) -> EmergencyStopState:
        """Whether the stop is latched, why and since when, and which hosts were not told."""
        latch = self._manager.emergency_stop
        untold = list(self._host_latches.untold)
        if latch is None:
            return EmergencyStopState(latched=False, untold_hosts=untold)
        return EmergencyStopState(latched=True, reason=latch.reason, time=latch.time, untold_hosts=untold)

    async def _save(self, latch: EmergencyStop) -> bool:
        """Save the latch for the next start; False (and a log entry) if the store failed."""
        try:
            await self._store.set_value(EMERGENCY_STOP_KEY, latch.model_dump(mode="json"))
        except (sqlite3.Error, StoreClosedError):
            log.exception("the emergency stop is latched, but could not be saved: a restart would forget it")
            return False
        return True


async def stored_emergency_stop(store: EventStore) -> EmergencyStop | None:
    """The emergency stop latched before this start, if any.

    A stored latch this version cannot read stays latched (with a reason saying so): only a
    person may unlatch it.
    """
    stored = await store.get_value(EMERGENCY_STOP_KEY)
    if stored is None:
        return None
    try:
        return EmergencyStop.model_validate(stored)
    except ValidationError:
        return EmergencyStop(
            reason=f"a stored emergency stop could not be read ({json.dumps(stored)[:200]})",
            time=datetime.now(UTC),
        )
