"""A person's "stop" acts the moment it is received, not when the kernel gets to it.

The kernel handles one event at a time, and an LLM turn can take seconds. A "stop" queued behind
such a turn would let the robot walk on for all that time. So the intake (:mod:`rosaos.kernel.intake`)
hands every new user text to :meth:`StopAtIntake.heard` right after it is committed: a text the
stop lexicon reads as a stop (:func:`rosaos.intents.understanding.stop_words.read_stop`) runs the
same :class:`~rosaos.kernel.stopping.Stopper` as the ``stop`` kernel tool at once (named devices,
or everything busy for a bare "stop"), in a task of its own, beside whatever the kernel is doing.

The event still goes through the queue like any other: the kernel sees it in its history and
answers it. When its turn calls ``stop`` for that event, the tool's report includes what the
intake stop already did (:meth:`StopAtIntake.merged`), so the reply says what was stopped and
which task ended, and the offline engine stays silent on the callback of the process it ended.
A stop's other commands ("stop the dog and turn on the light") are left to the kernel.

Names the user gave ("call the dog Rex") are read here as the engine reads them: "Rex, stop" is
"the dog, stop", so it acts at intake like any other stop (the aliases are read from the memory
store at each event, so a name given a moment ago counts).
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Awaitable, Callable, Mapping
from typing import Any

from rosaos.devices.world import World
from rosaos.events.types import UserSaidEvent, UserTypedEvent
from rosaos.intents.grammar.vocabulary import device_vocabularies
from rosaos.intents.understanding.stop_words import DeviceRefs, read_stop
from rosaos.kernel.stopping import StopError, StoppedDevice, Stopper, StopReport
from rosaos.kernel.updates import UpdateKind
from rosaos.memory.memory_phrases import resolve_aliases

log = logging.getLogger(__name__)

Publish = Callable[[UpdateKind, str, dict[str, Any], int], Awaitable[int]]
"""``UpdateStream.publish`` with the event id positional: (kind, text, data, event_id)."""

KEPT_REPORTS = 64
"""Intake stops remembered for the kernel's turn; older ones are forgotten (their turn is long done)."""


class StopAtIntake:
    """Runs stops at intake, and remembers each one by event id for the kernel's own ``stop``."""

    def __init__(
        self,
        stopper: Stopper,
        refs: DeviceRefs,
        publish: Publish,
        aliases: Callable[[], Mapping[str, str]] = dict,
    ) -> None:
        self._stopper = stopper
        self._refs = refs
        self._publish = publish
        self._aliases = aliases
        self._stops: dict[int, asyncio.Task[StopReport | None]] = {}

    @classmethod
    def for_world(
        cls,
        stopper: Stopper,
        world: World,
        language: str,
        publish: Publish,
        aliases: Callable[[], Mapping[str, str]] = dict,
    ) -> StopAtIntake:
        """Reading stops with the world's device names and the user's ``aliases`` (alias → what it
        names), as the offline engine does (any kernel model)."""
        return cls(stopper, DeviceRefs(device_vocabularies(world), language), publish, aliases)

    def heard(self, event_id: int, event: object) -> None:
        """A new event was committed: if it is user text that means stop, start stopping now.

        Returns at once (the stop runs in its own task), so the intake's answer is not delayed
        by a device that is slow to confirm its ``safe_stop``.
        """
        if not isinstance(event, UserTypedEvent | UserSaidEvent) or event_id in self._stops:
            return
        try:
            request = read_stop(resolve_aliases(event.payload.text, self._aliases()), self._refs)
        except Exception:  # the kernel's own reading will still see the event: never fail intake
            log.exception("could not read event %s as a stop", event_id)
            return
        if request is None:
            return
        self._stops[event_id] = asyncio.create_task(
            self._stop(event_id, request.devices, time.monotonic()), name=f"stop at intake {event_id}"
        )
        while len(self._stops) > KEPT_REPORTS:
            oldest = next(iter(self._stops))
            if not self._stops[oldest].done():
                break
            del self._stops[oldest]

    async def _stop(self, event_id: int, devices: tuple[str, ...], heard: float) -> StopReport | None:
        halted: dict[str, float] = {}

        def answered(device: str) -> None:
            halted[device] = round(time.monotonic() - heard, 3)

        try:
            report = await self._stopper.stop(devices, answered)
        except StopError as error:  # a name the world lost since: the kernel's turn says so
            log.warning("stop at intake for event %s: %s", event_id, error)
            return None
        except Exception:
            log.exception("stop at intake for event %s failed; the kernel's turn stops again", event_id)
            return None
        data: dict[str, Any] = {
            "tool": "stop",
            "at_intake": True,
            "args": {"devices": list(devices)},
            "result": report.model_dump(mode="json"),
            "seconds": round(time.monotonic() - heard, 3),
            # from intake to every holder ended and every safe_stop answered
            "safe_stop_seconds": halted,
            # from intake to each device's safe_stop answered: the moment that robot is stopped
        }
        try:
            await self._publish("tool_call", f"stopped at once: {report.summary}", data, event_id)
        except Exception:
            log.exception("could not publish the stop at intake for event %s", event_id)
        return report

    async def earlier(self, event_id: int | None) -> StopReport | None:
        """What the intake stop did for ``event_id`` (waiting for it to finish), or None."""
        task = self._stops.get(event_id) if event_id is not None else None
        return await task if task is not None else None

    async def merged(self, event_id: int | None, report: StopReport) -> StopReport:
        """``report`` of the kernel's own stop, with what the intake stop did for the same event first.

        The kernel's stop then found the devices idle and their holders gone; the intake stop's
        account of them (what each was doing, which process ended) is the one worth telling.
        """
        first = await self.earlier(event_id)
        if first is None:
            return report
        later = {device.device: device for device in report.devices}
        devices = [_confirmed(device, later.get(device.device)) for device in first.devices]
        devices += [device for name, device in later.items() if name not in {d.device for d in first.devices}]
        ended = list({process.id: process for process in [*first.terminated, *report.terminated]}.values())
        if not devices and not ended:
            return report
        summary = self._stopper.summary(devices, ended, explicit=True, names=[])
        return StopReport(devices=devices, terminated=ended, summary=summary)


def _confirmed(first: StoppedDevice, later: StoppedDevice | None) -> StoppedDevice:
    """The intake stop's account of a device, confirmed if the kernel's later safe_stop answered."""
    if first.safe_stop or later is None or not later.safe_stop:
        return first
    return first.model_copy(update={"safe_stop": True, "detail": later.detail})
