"""A person's "stop": the kernel preempts whatever holds a device, and needs no lease.

A robot told to stop must stop at once, whoever holds it. Launching a process for it would be
refused while another process holds the robot, which is exactly when it moves. So "stop" is a
kernel action (the ``stop`` kernel tool, planned by the offline engine too): for each device it
terminates the processes that hold it and calls the device's ``safe_stop``, both at once.

Which devices, and in what order:

- named devices ("stop the dog", "stop the music"): those, and nothing else. Each gets
  ``safe_stop`` whatever it was doing (an explicit stop costs nothing if it was idle).
- nothing named (a bare "stop", "stop everything"): everything that is busy, in the order of
  :data:`rosaos.drivers.Halt`: every robot in motion first, then what speaks, then what plays;
  then every other running process is terminated too. A device is busy when a process holds it
  or its state says so (:func:`rosaos.intents.grammar.state_words.doing`); an idle one is left alone, so a
  bare "stop" does not freeze a companion robot's idle motion nobody asked to stop.

The always-attached device (the Reachy Mini) is held by every process, so holding it says
nothing about what it does: its processes are not terminated for it, only its ``safe_stop`` runs.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from pydantic import BaseModel

from rosaos.devices.client import DeviceClient
from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.drivers import DeviceError, Halt
from rosaos.intents.grammar.state_words import called, doing
from rosaos.processes.manager import ProcessInfo, ProcessManager

HALT_ORDER: tuple[Halt, ...] = ("motion", "speech", "sound")
SAFE_STOP_TIMEOUT = 3.0
"""Seconds a device's ``safe_stop`` may take before the stop reports it as not confirmed."""
STATE_TIMEOUT = 1.0
"""Seconds to read an unheld device's state to learn whether it is busy (bare "stop" only)."""
TASK_WORDS = 120


class StoppedProcess(BaseModel):
    """A process the stop terminated: its id and what it was doing, in words."""

    id: int
    task: str


class StoppedDevice(BaseModel):
    """One device the stop reached."""

    device: str
    was: str | None = None
    """What it was doing: "moving", "speaking", "playing", or the task of the process holding it."""
    processes: list[StoppedProcess] = []
    safe_stop: bool
    """Whether its ``safe_stop`` answered; False with the reason in ``detail``."""
    detail: str = ""


class StopReport(BaseModel):
    """What a stop did, and one sentence that says it (the reply)."""

    devices: list[StoppedDevice]
    terminated: list[StoppedProcess]
    """Every process the stop terminated, those of ``devices`` included."""
    summary: str


class StopError(ValueError):
    """A stop that names devices the world does not have; the message lists the ones it has."""


class Stopper:
    """Runs stops against the kernel's process manager and devices."""

    def __init__(
        self,
        manager: ProcessManager,
        endpoints: Callable[[], Mapping[str, DeviceEndpoint]],
        halts: Callable[[str], Sequence[Halt]],
    ) -> None:
        self._manager = manager
        self._endpoints = endpoints
        self._halts = halts

    def _called(self, name: str) -> str:
        """How the reply names a device: "the kitchen light", but "Spotify" (:func:`called`)."""
        endpoint = self._endpoints().get(name)
        return called(name, endpoint.driver if endpoint is not None else "")

    async def stop(
        self, devices: Sequence[str] = (), answered: Callable[[str], None] | None = None
    ) -> StopReport:
        """Stop ``devices``, or everything busy when none is named (see the module docstring).

        ``answered(name)`` is called the moment a device's ``safe_stop`` answers: the robot is
        stopped then, while its process may still be ending (the stop at intake times both).
        """
        endpoints = self._endpoints()
        unknown = [name for name in devices if name not in endpoints]
        if unknown:
            raise StopError(
                f"no device named {', '.join(map(repr, unknown))}; the devices are {', '.join(endpoints)}"
            )
        explicit = bool(devices)
        names = list(dict.fromkeys(devices)) if explicit else list(endpoints)
        terminated: dict[int, StoppedProcess] = {}
        stopped: list[StoppedDevice] = []
        for rank in range(len(HALT_ORDER) + 1):
            group = [name for name in names if self._rank(name) == rank]
            if not explicit and rank == len(HALT_ORDER):
                break  # a bare stop halts devices that halt something; the rest are processes only
            results = await asyncio.gather(
                *(self._stop_one(endpoints[name], explicit, terminated, answered) for name in group)
            )
            stopped += [result for result in results if result is not None]
        if not explicit:
            rest = [info for info in self._manager.list() if info.id not in terminated]
            await asyncio.gather(*(self._terminate(info, terminated) for info in rest))
        summary = self.summary(stopped, list(terminated.values()), explicit, names)
        return StopReport(devices=stopped, terminated=list(terminated.values()), summary=summary)

    def _rank(self, name: str) -> int:
        halts = self._halts(name)
        return min((HALT_ORDER.index(halt) for halt in halts), default=len(HALT_ORDER))

    async def _stop_one(
        self,
        endpoint: DeviceEndpoint,
        explicit: bool,
        terminated: dict[int, StoppedProcess],
        answered: Callable[[str], None] | None,
    ) -> StoppedDevice | None:
        holders = [] if endpoint.always_attached else self._holders(endpoint.name)
        was: str | None = None
        if not holders:
            state = await self._state(endpoint)
            was = doing(state)
            if was is None and not explicit:
                return None
        ended = asyncio.gather(*(self._terminate(info, terminated) for info in holders))
        (ok, detail), processes = await asyncio.gather(self._safe_stop(endpoint, answered), ended)
        if processes:
            was = processes[0].task
        return StoppedDevice(
            device=endpoint.name, was=was, processes=list(processes), safe_stop=ok, detail=detail
        )

    def _holders(self, name: str) -> list[ProcessInfo]:
        return [info for info in self._manager.list() if name in info.devices]

    async def _terminate(self, info: ProcessInfo, terminated: dict[int, StoppedProcess]) -> StoppedProcess:
        if info.id not in terminated:
            terminated[info.id] = StoppedProcess(id=info.id, task=describe_task(info.task))
            with contextlib.suppress(KeyError):  # it ended meanwhile: nothing left to terminate
                await self._manager.terminate(info.id)
        return terminated[info.id]

    async def _state(self, endpoint: DeviceEndpoint) -> dict[str, Any] | None:
        if endpoint.url is None:
            return None
        client = DeviceClient(endpoint.url, endpoint.token, STATE_TIMEOUT, endpoint.name)
        try:
            return await asyncio.wait_for(client.get_state(), STATE_TIMEOUT)
        except (DeviceError, TimeoutError):
            return None

    async def _safe_stop(
        self, endpoint: DeviceEndpoint, answered: Callable[[str], None] | None = None
    ) -> tuple[bool, str]:
        if endpoint.url is None:
            return True, f"not served ({endpoint.status}): nothing runs on it"
        client = DeviceClient(endpoint.url, endpoint.token, SAFE_STOP_TIMEOUT, endpoint.name)
        try:
            detail = await asyncio.wait_for(client.call("safe_stop"), SAFE_STOP_TIMEOUT)
        except (DeviceError, TimeoutError) as error:
            return False, str(error) or f"safe_stop did not answer within {SAFE_STOP_TIMEOUT:g} s"
        if answered is not None:
            answered(endpoint.name)
        return True, str(detail)

    def summary(
        self,
        stopped: list[StoppedDevice],
        terminated: list[StoppedProcess],
        explicit: bool,
        names: list[str],
    ) -> str:
        """One sentence per device stopped, then the other tasks ended (the stop's reply)."""
        sentences = []
        for device in stopped:
            the = self._called(device.device)
            if device.processes:
                tasks = "; ".join(f"'{p.task}' (process {p.id})" for p in device.processes)
                sentence = f"Stopped {the}: it was doing {tasks}, now terminated."
            elif device.was in ("moving", "speaking", "playing"):
                sentence = f"Stopped {the}: it was {device.was}."
            else:
                sentence = f"Sent {the} a stop; it was not doing anything."
            if not device.safe_stop:
                sentence += f" Its safe stop is NOT confirmed: {device.detail}"
            sentences.append(sentence)
        shown = {p.id for device in stopped for p in device.processes}
        others = [p for p in terminated if p.id not in shown]
        if others:
            tasks = "; ".join(f"'{p.task}' (process {p.id})" for p in others)
            sentences.append(f"Terminated {tasks}.")
        if not sentences:
            if explicit:
                listed = ", ".join(self._called(name) for name in names)
                return f"Nothing to stop on {listed}."
            return "Nothing was moving, speaking or playing, and no task was running."
        return " ".join(sentences)


def describe_task(task: str) -> str:
    """A process's task in a few words: its readable summary's first line, shortened."""
    first = task.strip().splitlines()[0] if task.strip() else ""
    first = first.strip().rstrip(".")
    if len(first) > TASK_WORDS:
        first = first[: TASK_WORDS - 1].rstrip() + "…"
    return first or "a task"
