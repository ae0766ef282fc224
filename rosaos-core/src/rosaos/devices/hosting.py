"""What the kernel needs from whatever serves its devices.

:class:`~rosaos.devices.supervisor.DeviceSupervisor` (one host process per device, or a shared
one) in ``rosaos up``; :class:`~rosaos.bench.sim_world.SimDevices` (simulators served in the
kernel's own process) in the task benchmark. The kernel uses both the same way, with no
``isinstance`` check: what only the supervisor needs to do, the simulators do trivially.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Protocol

from rosaos.devices.supervisor import DirectoryEntry, SafeStopOutcome, StatusListener


class DeviceHosting(Protocol):
    """Serves the world's devices; see the module docstring for the two implementations."""

    version: int
    """Bumped whenever a device's status, URL or error changes (the kernel caches until then)."""
    on_status_change: StatusListener | None
    """Called as ``(instance, old, new, error)`` when a device's status changes."""

    async def start(self, wait: bool = True) -> None:
        """Serve the devices; may return before background-start ones are up (see :meth:`settle`).

        With ``wait=False`` it returns as soon as the devices are starting (``rosaos up``'s early
        banner): each becomes grantable as it comes up."""

    async def stop(self) -> None:
        """Stop serving every device; safe to call when :meth:`start` never ran or failed."""

    def directory(self) -> dict[str, DirectoryEntry]:
        """Every instance with its URL, token and status."""

    async def safe_stop_all(self) -> list[SafeStopOutcome]:
        """Call ``safe_stop`` on every device (the emergency stop)."""

    async def foreground_settled(self) -> None:
        """Wait until every device but the background-start ones has had its first start attempt."""

    def release_background(self) -> None:
        """Let devices that boot in the background start now (the kernel's other parts are up)."""

    async def settle(self, names: Iterable[str]) -> None:
        """Wait until each named device has had its first start attempt."""

    def host_of(self, name: str) -> str:
        """The host that serves ``name``: devices on one host go down together."""
