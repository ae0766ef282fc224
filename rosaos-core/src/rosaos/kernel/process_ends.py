"""A process's end, from the pool's report to the queue and what its arrival sets off.

The pool reports each end once (:mod:`rosaos.processes.watcher`); :func:`end_event` makes it a
``worker_callback`` event with the key ``process-<id>``, which the kernel queues through its
intake. Orphan recovery queues a dead kernel's processes the same way. :class:`ProcessEnds` is
the intake's side effect for that kind: it runs once the end is committed, for a duplicate too,
so everything in it is idempotent.
"""

from __future__ import annotations

from rosaos.events.types import WorkerCallbackEvent
from rosaos.kernel.activity import ActivityLog
from rosaos.kernel.intake import Queued
from rosaos.kernel.orphans import LiveProcesses
from rosaos.kernel.updates import UpdateStream
from rosaos.memory.sightings import SightingLog
from rosaos.processes.jobs import WorkerCallback, callback_idempotency_key
from rosaos.processes.manager import ProcessManager


def end_event(callback: WorkerCallback, source: str = "worker") -> WorkerCallbackEvent:
    """The ``worker_callback`` event that queues ``callback``; its key makes it queue once."""
    return WorkerCallbackEvent(
        kind="worker_callback",
        source=source,
        payload=callback,
        idempotency_key=callback_idempotency_key(callback.process_id),
    )


class ProcessEnds:
    """What a committed process end sets off: leases released, activity and sightings recorded,
    ``process_ended`` published once, and the process forgotten by orphan recovery."""

    def __init__(
        self,
        manager: ProcessManager,
        activity: ActivityLog,
        sightings: SightingLog,
        updates: UpdateStream,
        live: LiveProcesses,
    ) -> None:
        self._manager = manager
        self._activity = activity
        self._sightings = sightings
        self._updates = updates
        self._live = live
        self._published: set[int] = set()

    async def arrived(self, queued: Queued) -> None:
        """The intake's effect for a ``worker_callback`` event (see the module docstring)."""
        callback = queued.event.payload
        if not isinstance(callback, WorkerCallback):
            raise TypeError(f"event {queued.id} is a {queued.event.kind}, not a worker_callback")
        self._manager.record_callback(callback)  # leases free before the kernel reads the event
        await self._activity.record(queued.id, callback.process_id, callback.receipts)
        self._sightings.record_receipts(callback.receipts)  # the people its robots saw
        if callback.process_id not in self._published:
            self._published.add(callback.process_id)
            text = f"process {callback.process_id} ended: {callback.status}"
            if callback.error:
                text += f" ({callback.error})"
            await self._updates.publish(
                "process_ended", text, callback.model_dump(mode="json"), event_id=queued.id
            )
        # Forgotten only once its end is on the updates stream: a kill before this line leaves the
        # record, and the restart publishes the committed callback (kernel/orphans.py).
        await self._live.ended(callback.process_id)
