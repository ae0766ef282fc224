"""The one way into the kernel's queue: append, publish, then run the event's side effects.

Every event enters here, whoever sends it: the HTTP routes (``/chat``, ``/stt``, ``/event``), the
pool reporting a process's end, orphan recovery at start-up, the notice watcher and the timers.
:meth:`Intake.submit` does the same three steps for each:

1. **append** it to the event store (committed before anything else happens; a known idempotency
   key answers the first event instead, which is what the later steps then see);
2. **publish** it on the updates stream, once (not again for a duplicate): its ``event`` update is
   written in the append's own transaction (one trip to the database thread) and handed to the
   followers once committed;
3. **side effects**: the effects registered for its kind, in order (:meth:`Intake.on`).

Step 3 is the spot for whatever must happen when an event arrives rather than when the kernel
agent gets to it: the kernel loop reads the queue on its own, so an effect runs whether or not a
turn is under way. Today a ``worker_callback`` releases its process's leases and records its
activity there; the stop fast path (a spoken or typed "stop" obeyed at once) belongs there too.
An effect that fails is logged and put on the updates stream; it never un-queues the event.
"""

from __future__ import annotations

import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

from rosaos.events.types import EventKind, NewEvent
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.updates import UpdateStream

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Queued:
    """An event as the intake took it: its id, and the event the queue holds under that id."""

    id: int
    event: NewEvent
    """For a duplicate, the first event with that key (the one the kernel will read), not the retry."""
    duplicate: bool = False
    conflict: bool = False
    """The idempotency key was used before for a different body (the API answers 409). As for any
    duplicate, the effects ran with the first event: orphan recovery's guess ``crashed`` for a
    process whose own end was committed is such a conflict, and the committed end is what counts."""


Effect = Callable[[Queued], Awaitable[None]]
"""A side effect of an event's arrival; runs for duplicates too, so it must be idempotent."""


class Intake:
    """Takes events into the queue; see the module docstring for the three steps."""

    def __init__(self, store: EventStore, updates: UpdateStream) -> None:
        self._store = store
        self._updates = updates
        self._effects: dict[EventKind, list[Effect]] = {}

    def on(self, kind: EventKind, effect: Effect) -> None:
        """Run ``effect`` for every event of ``kind`` once it is committed and published."""
        self._effects.setdefault(kind, []).append(effect)

    async def submit(self, event: NewEvent) -> Queued:
        """Queue ``event``, publish it, run its side effects; return where it is in the queue.

        Raises only if the append itself fails (nothing was queued then): once the event is
        committed, a failure to publish or in an effect is logged, so a caller never retries an
        event that is already queued.
        """
        update = self._updates.event_update(event)
        appended = await self._store.append(event, also=update.write)
        queued = Queued(appended.id, event)
        if appended.duplicate:
            first = await self._first(appended.id, event)
            queued = Queued(appended.id, first, duplicate=True, conflict=appended.conflict)
        else:
            try:
                update.offer()
            except Exception:
                log.exception("could not publish the update for event %s", appended.id)
        for effect in self._effects.get(event.kind, ()):
            await self._run(effect, queued)
        return queued

    async def _first(self, event_id: int, retry: NewEvent) -> NewEvent:
        """The event the queue holds for a duplicate's key (same kind: a different one is a conflict)."""
        stored = await self._store.get(event_id)
        if stored is None or stored.kind != retry.kind:
            return retry
        return retry.model_copy(update={"payload": stored.payload, "source": stored.source})

    async def _run(self, effect: Effect, queued: Queued) -> None:
        try:
            await effect(queued)
        except Exception as error:
            log.exception("a side effect of event %s (%s) failed", queued.id, queued.event.kind)
            try:
                await self._updates.publish(
                    "error", f"event {queued.id} is queued, but handling its arrival failed: {error}"
                )
            except Exception:
                log.exception("could not publish that failure either")
