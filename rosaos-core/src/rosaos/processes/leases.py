"""Device leases: which live process holds which device, enforced in code, never left to the model.

A device declares its concurrency (:data:`rosaos.drivers.Concurrency`): an ``exclusive`` device is
held by at most one live process, a ``shared`` one by any number. A grant is all-or-nothing: a
process gets every device it asked for (plus the always-attached ones its task asks for, see
:func:`attaches`) or none, so it never starts with half of what its task needs. Refusals say who holds what, so the kernel agent can wait, ask
the user, or terminate the holder.

The table is plain synchronous data: the process manager calls it from the event loop, and a
grant or release never awaits, so no lock is needed.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from rosaos.devices.endpoints import DeviceEndpoint


class LeaseRefused(Exception):
    """A grant that cannot be made. The message says why and what the kernel can do about it."""

    def __init__(self, message: str, *, holders: Mapping[str, Lease] | None = None) -> None:
        super().__init__(message)
        self.holders: dict[str, Lease] = dict(holders or {})
        """Exclusive devices that were refused because another process holds them."""


@dataclass(frozen=True)
class Lease:
    """One device held by one process."""

    device: str
    process_id: int
    task: str


class LeaseTable:
    """The leases of all live processes."""

    def __init__(self) -> None:
        self._leases: dict[int, list[Lease]] = {}
        self._by_device: dict[str, list[Lease]] = {}
        """The same leases by device: a grant looks its devices up, it does not walk every lease."""
        self._attached: tuple[Mapping[str, DeviceEndpoint], list[str]] | None = None
        """The always-attached devices of the last device map (the kernel's is rebuilt only when a
        device changes): a burst of grants does not walk a hundred devices each."""

    def acquire(
        self,
        process_id: int,
        task: str,
        requested: Iterable[str],
        devices: Mapping[str, DeviceEndpoint],
    ) -> list[str]:
        """Grant ``requested`` plus every always-attached device to ``process_id``, all or nothing.

        Returns the granted device names: the requested ones in the order asked, then the
        always-attached ones that were not asked for and that ``task`` asks for (:func:`attaches`),
        or all of them when no device was asked for (speaking is all such a process can do). Raises :class:`LeaseRefused` naming every
        problem (unknown device, device not served, exclusive device held by another process).
        An always-attached device that is not served right now is left out rather than refused:
        the process can still do its task, it just cannot talk to the user.
        """
        if process_id in self._leases:
            raise ValueError(f"process {process_id} already holds leases; process ids must be new")
        wanted = list(dict.fromkeys(requested))

        unknown = [name for name in wanted if name not in devices]
        if unknown:
            known = ", ".join(sorted(devices)) or "none"
            names = ", ".join(repr(name) for name in unknown)
            noun = "device" if len(unknown) == 1 else "devices"
            raise LeaseRefused(f"unknown {noun} {names}; the devices are: {known}")

        problems: list[str] = []
        for name in wanted:
            device = devices[name]
            if not device.grantable and device.status == "starting":
                problems.append(
                    f"{name} is still starting (its host has not reported it ready); "
                    "try again in a few seconds, or see `rosaos devices list`"
                )
            elif not device.grantable:
                problems.append(
                    f"{name} is not available now (status: {device.status}); "
                    "choose another device, or try again once it is healthy"
                )
        implicit = [
            name
            for name in self._always_attached(devices)
            if devices[name].grantable
            and name not in wanted
            and (not wanted or attaches(devices[name], task))
        ]
        granted = wanted + implicit

        held: dict[str, Lease] = {}
        for name in granted:
            holder = self._exclusive_holder(name, devices[name])
            if holder is not None:
                held[name] = holder
                problems.append(
                    f"{name} is held by process {holder.process_id} ({_headline(holder.task)!r}); "
                    f"wait for it, or terminate_process({holder.process_id})"
                )
        if problems:
            raise LeaseRefused("\n".join(problems), holders=held)

        self._leases[process_id] = [Lease(name, process_id, task) for name in granted]
        for lease in self._leases[process_id]:
            self._by_device.setdefault(lease.device, []).append(lease)
        return granted

    def release(self, process_id: int) -> list[str]:
        """Release every device ``process_id`` holds; returns their names. Releasing twice is fine."""
        released = self._leases.pop(process_id, [])
        for lease in released:
            remaining = [held for held in self._by_device.get(lease.device, []) if held is not lease]
            if remaining:
                self._by_device[lease.device] = remaining
            else:
                self._by_device.pop(lease.device, None)
        return [lease.device for lease in released]

    def _always_attached(self, devices: Mapping[str, DeviceEndpoint]) -> list[str]:
        if self._attached is None or self._attached[0] is not devices:
            self._attached = (devices, [name for name, device in devices.items() if device.always_attached])
        return self._attached[1]

    def held_by(self, process_id: int) -> list[str]:
        """The devices ``process_id`` holds, in grant order (empty when it holds none)."""
        return [lease.device for lease in self._leases.get(process_id, [])]

    def holders(self) -> dict[str, list[Lease]]:
        """Every held device and the leases on it (several for a shared device)."""
        by_device: dict[str, list[Lease]] = {}
        for leases in self._leases.values():
            for lease in leases:
                by_device.setdefault(lease.device, []).append(lease)
        return by_device

    def _exclusive_holder(self, name: str, device: DeviceEndpoint) -> Lease | None:
        if device.concurrency != "exclusive":
            return None
        leases = self._by_device.get(name)
        return leases[0] if leases else None


def attaches(device: DeviceEndpoint, task: str) -> bool:
    """Whether always-attached ``device`` goes to a process whose task is ``task`` unasked: always,
    unless its driver names the words a task asks for it by (``DriverSpec.attached_pattern``)."""
    pattern = device.attached_pattern
    return pattern is None or re.search(pattern, task, re.IGNORECASE) is not None


def _headline(task: str, limit: int = 80) -> str:
    """A task's first line, short: a refusal names the holder's task, not its whole plan."""
    line = task.strip().splitlines()[0] if task.strip() else ""
    return line if len(line) <= limit else line[: limit - 1] + "…"
