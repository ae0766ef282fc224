"""A device host going down, and coming back, is news for whoever watches the updates stream.

The supervisor restarts a crashed or stuck host by itself; the web page and ``rosaos chat``
should still see that a device was gone for a while, and when it answers again.
"""

from __future__ import annotations

import asyncio
import logging

from rosaos.devices.run_files import DeviceStatus
from rosaos.kernel.updates import UpdateStream

log = logging.getLogger("rosaos.kernel.device_status")

DOWN: frozenset[DeviceStatus] = frozenset({"unhealthy", "restarting", "failed", "unreachable"})


class DeviceStatusUpdates:
    """Publishes ``notice`` updates when a device goes down and when it is back (supervisor listener)."""

    def __init__(self, updates: UpdateStream) -> None:
        self._updates = updates
        self._down: set[str] = set()
        self._publishing: set[asyncio.Task[None]] = set()

    def changed(self, name: str, old: DeviceStatus, new: DeviceStatus, error: str | None) -> None:
        """The supervisor's ``on_status_change``: say it once when down, once when back."""
        if new in DOWN and name not in self._down:
            self._down.add(name)
            reason = f": {error}" if error else ""
            self._publish(f"device {name} is down ({new}{reason}); rosaOS is restarting it", name, new, error)
        elif new == "healthy" and name in self._down:
            self._down.discard(name)
            self._publish(f"device {name} is back", name, new, None)

    def _publish(self, text: str, name: str, status: DeviceStatus, error: str | None) -> None:
        data = {"device": name, "status": status, "error": error}
        task = asyncio.get_running_loop().create_task(self._send(text, data))
        self._publishing.add(task)
        task.add_done_callback(self._publishing.discard)

    async def _send(self, text: str, data: dict[str, str | None]) -> None:
        try:
            await self._updates.publish("notice", text, data)
        except Exception:  # the store may be closing at shutdown; the supervisor's log has it too
            log.exception("could not publish %r", text)
