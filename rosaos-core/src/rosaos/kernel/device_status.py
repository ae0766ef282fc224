"""A device host going down, and coming back, is news for whoever watches the updates stream.

The supervisor restarts a crashed or stuck host by itself; the web page and ``rosaos chat``
should still see that a device was gone for a while, and when it answers again.

One host may serve a hundred simulated devices, and they go down together. So changes are
gathered for ``window`` seconds and published per host and direction: one notice "12 devices on
host shared-sims are not answering …" rather than twelve, and one when they are back. A device
that goes down and comes back within the same window was never news and is not published at all.
One device alone keeps the plain wording ("device lamp is down (…)", "device lamp is back").
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from typing import Any

from rosaos.devices.run_files import DeviceStatus
from rosaos.kernel.updates import UpdateStream

log = logging.getLogger("rosaos.kernel.device_status")

DOWN: frozenset[DeviceStatus] = frozenset({"unhealthy", "restarting", "failed", "unreachable"})

WINDOW = 1.0
"""Seconds of status changes gathered into one notice per host."""

SHOWN = 10
"""Device names listed in one notice; the rest are counted."""


def _own_host(name: str) -> str:
    return name


class DeviceStatusUpdates:
    """Publishes coalesced ``notice`` updates when devices go down and when they are back.

    ``changed`` is the supervisor's ``on_status_change``; ``host_of`` names the host that serves
    a device (:meth:`~rosaos.devices.supervisor.DeviceSupervisor.host_of`).
    """

    def __init__(
        self, updates: UpdateStream, host_of: Callable[[str], str] = _own_host, window: float = WINDOW
    ) -> None:
        self._updates = updates
        self._host_of = host_of
        self.window = window
        self._down: set[str] = set()
        """Devices whose going down was published (or is about to be)."""
        self._going_down: dict[str, tuple[DeviceStatus, str | None]] = {}
        self._coming_back: set[str] = set()
        self._flush: asyncio.TimerHandle | None = None
        self._publishing: set[asyncio.Task[None]] = set()
        self.published = 0
        """Notices published so far (for tests and benchmarks)."""

    def changed(self, name: str, old: DeviceStatus, new: DeviceStatus, error: str | None) -> None:
        """The supervisor's ``on_status_change``: note the change; it is published with its host's."""
        if new in DOWN and name not in self._down:
            self._down.add(name)
            if name in self._coming_back:  # back and down again within one window: no news
                self._coming_back.discard(name)
            else:
                self._going_down[name] = (new, error)
        elif new == "healthy" and name in self._down:
            self._down.discard(name)
            if self._going_down.pop(name, None) is None:  # announced before: say it is back
                self._coming_back.add(name)
        else:
            return
        if self._flush is None:
            self._flush = asyncio.get_running_loop().call_later(self.window, self._publish_gathered)

    def _publish_gathered(self) -> None:
        self._flush = None
        down, self._going_down = self._going_down, {}
        back, self._coming_back = self._coming_back, set()
        for host, names in _by_host(down, self._host_of).items():
            status, error = down[names[0]]
            self._publish(_down_text(host, names, status, error), names, host, status, error)
        for host, names in _by_host(back, self._host_of).items():
            self._publish(_back_text(host, names), names, host, "healthy", None)

    def _publish(
        self, text: str, names: list[str], host: str, status: DeviceStatus, error: str | None
    ) -> None:
        data: dict[str, Any] = {"device": names[0], "devices": names, "host": host, "status": status}
        data["error"] = error
        self.published += 1
        task = asyncio.get_running_loop().create_task(self._send(text, data))
        self._publishing.add(task)
        task.add_done_callback(self._publishing.discard)

    async def _send(self, text: str, data: dict[str, Any]) -> None:
        try:
            await self._updates.publish("notice", text, data)
        except Exception:  # the store may be closing at shutdown; the supervisor's log has it too
            log.exception("could not publish %r", text)


def _by_host(names: dict[str, Any] | set[str], host_of: Callable[[str], str]) -> dict[str, list[str]]:
    grouped: dict[str, list[str]] = {}
    for name in sorted(names):
        grouped.setdefault(host_of(name), []).append(name)
    return grouped


def _listed(names: list[str]) -> str:
    shown = ", ".join(names[:SHOWN])
    return shown if len(names) <= SHOWN else f"{shown} and {len(names) - SHOWN} more"


def _down_text(host: str, names: list[str], status: DeviceStatus, error: str | None) -> str:
    reason = f": {error}" if error else ""
    if len(names) == 1:
        return f"device {names[0]} is down ({status}{reason}); rosaOS is restarting it"
    return (
        f"{len(names)} devices on host {host} are not answering ({status}{reason}): "
        f"{_listed(names)}; rosaOS is restarting them"
    )


def _back_text(host: str, names: list[str]) -> str:
    if len(names) == 1:
        return f"device {names[0]} is back"
    return f"{len(names)} devices on host {host} are back: {_listed(names)}"
