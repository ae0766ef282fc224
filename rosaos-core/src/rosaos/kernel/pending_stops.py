"""``safe_stop`` calls that could not be delivered, kept until they are: nothing is granted before.

An emergency stop, or the safe-stop of a dead kernel's orphans at restart, may find a device
unreachable (a silent network, a host being restarted). Its host's deadman stops a motion whose
owner went quiet, but the kernel does not take that on trust: the stop is written to the event
store as *pending*, retried every :data:`RETRY_PERIOD` s and before any launch that asks for the
device, and a launch is refused while it stays undelivered. Each delivery is reported on the
updates stream.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable, Iterable, Mapping
from datetime import UTC, datetime
from typing import Any

from rosaos.devices.directory import DirectoryEntry, SafeStopOutcome, safe_stop_entry
from rosaos.kernel.event_store import EventStore

log = logging.getLogger("rosaos.kernel.pending_stops")

PENDING_STOPS_KEY = "pending_safe_stops"
RETRY_PERIOD = 2.0


class StopUndelivered(Exception):
    """A device whose pending ``safe_stop`` could not be delivered yet; the message says so."""


class PendingStops:
    """The devices owed a ``safe_stop``, in the event store so a restart still owes them."""

    def __init__(
        self,
        store: EventStore,
        directory: Callable[[], Mapping[str, DirectoryEntry]],
        report: Callable[[str, dict[str, Any]], Awaitable[Any]],
    ) -> None:
        self._store = store
        self._directory = directory
        self._report = report
        self._lock = asyncio.Lock()
        self._pending: dict[str, dict[str, str]] | None = None
        """The store's value, read once: this kernel is its only writer, and every launch asks
        (a read per launch was a database hop on the way from a command to its worker)."""

    async def note(self, outcomes: Iterable[SafeStopOutcome]) -> None:
        """Remember every outcome that failed; forget the devices whose stop got through."""
        async with self._lock:
            pending = await self._read()
            for outcome in outcomes:
                if outcome.ok:
                    pending.pop(outcome.instance, None)
                else:
                    pending.setdefault(outcome.instance, {"since": datetime.now(UTC).isoformat()})
                    pending[outcome.instance]["detail"] = outcome.detail
            await self._save(pending)

    async def names(self) -> list[str]:
        return sorted(await self._read())

    async def deliver(self, names: Iterable[str] | None = None) -> list[str]:
        """Retry the pending stops (of ``names``, or all); return the devices still owed one."""
        async with self._lock:
            pending = await self._read()
            wanted = [name for name in (pending if names is None else names) if name in pending]
            if not wanted:
                return []
            directory = self._directory()
            tries = [name for name in wanted if name in directory]
            outcomes = await asyncio.gather(*(safe_stop_entry(directory[name]) for name in tries))
            still = [name for name in wanted if name not in directory]
            for outcome in outcomes:
                if not outcome.ok:
                    pending[outcome.instance]["detail"] = outcome.detail
                    still.append(outcome.instance)
                    continue
                since = pending.pop(outcome.instance).get("since", "earlier")
                text = f"{outcome.instance}: the safe_stop that could not be delivered ({since}) was retried and done"
                log.warning("%s", text)
                await self._report(text, {"device": outcome.instance, "pending_since": since})
            await self._save(pending)
            return still

    async def before_grant(self, names: Iterable[str]) -> None:
        """Deliver what ``names`` are owed; raise :class:`StopUndelivered` if one still is."""
        still = await self.deliver(names)
        if still:
            raise StopUndelivered(
                f"{', '.join(still)} still owe{'s' if len(still) == 1 else ''} a safe_stop that could not be "
                "delivered (the device did not answer); nothing is granted before it lands. It is retried "
                "every few seconds: check the device's host and network (rosaos devices list)"
            )

    async def run(self) -> None:
        """Retry every :data:`RETRY_PERIOD` s until cancelled, so a device that comes back is stopped."""
        while True:
            await asyncio.sleep(RETRY_PERIOD)
            try:
                await self.deliver()
            except Exception:
                log.exception("retrying the pending safe_stops failed")

    async def _read(self) -> dict[str, dict[str, str]]:
        if self._pending is None:
            stored = await self._store.get_value(PENDING_STOPS_KEY)
            self._pending = (
                {str(k): dict(v) for k, v in stored.items() if isinstance(v, dict)}
                if isinstance(stored, dict)
                else {}
            )
        return self._pending

    async def _save(self, pending: dict[str, dict[str, str]]) -> None:
        try:
            await self._store.set_value(PENDING_STOPS_KEY, pending)
        except BaseException:
            self._pending = None  # not written: the next read takes the store's word again
            raise
