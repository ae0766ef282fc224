"""How to reach a served instance, and stopping it safely: what the supervisor tells the kernel."""

from __future__ import annotations

from dataclasses import dataclass

from pydantic import BaseModel

from rosaos.devices.client import DeviceClient
from rosaos.devices.run_files import DeviceStatus
from rosaos.drivers import DeviceError


class DirectoryEntry(BaseModel):
    """How to reach one instance: what the kernel hands to a worker that is granted it."""

    name: str
    driver: str
    url: str | None
    """None while the instance is not being served (placeholder, failed, restarting)."""
    token: str | None
    status: DeviceStatus
    remote: bool
    error: str | None = None
    restarts: int = 0
    server_epoch: str | None = None
    """Names the server process serving it now (a new value: a new server, which knows no session
    opened before). None: the kernel cannot tell (a remote device), so a worker checks its kept
    session before each job (:class:`rosaos.processes.worker.DeviceSessions`)."""


@dataclass
class SafeStopOutcome:
    """The result of calling ``safe_stop`` on one instance."""

    instance: str
    ok: bool
    detail: str


async def safe_stop_entry(entry: DirectoryEntry, timeout: float = 5.0) -> SafeStopOutcome:
    """Call one served instance's ``safe_stop`` tool; a failure is reported, not raised."""
    if entry.url is None:
        return SafeStopOutcome(entry.name, True, f"not served ({entry.status}): nothing to stop")
    try:
        detail = await DeviceClient(entry.url, entry.token, timeout, entry.name).call("safe_stop")
    except DeviceError as error:
        return SafeStopOutcome(entry.name, False, str(error))
    return SafeStopOutcome(entry.name, True, str(detail))
