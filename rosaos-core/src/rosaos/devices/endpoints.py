"""The kernel's view of a device: what it can grant, and where a granted process reaches it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from rosaos.devices.run_files import DeviceStatus
from rosaos.drivers import Concurrency


@dataclass(frozen=True)
class DeviceEndpoint:
    """One device instance as the process manager sees it."""

    name: str
    driver: str
    concurrency: Concurrency
    always_attached: bool
    description: str
    prompt: str
    url: str | None
    """Streamable-HTTP MCP URL, or None while the instance is not served."""
    token: str
    status: DeviceStatus
    confirm: list[str] | Literal["destructive"] | None = None
    """What needs a person's yes (:func:`rosaos.confirmations.confirming.confirm_rule`)."""
    attached_tools: tuple[str, ...] = ()
    """For an always-attached device: the tools a process gets when the kernel did not ask for it."""
    attached_prompt: str | None = None
    """The device prompt that goes with :attr:`attached_tools`."""
    attached_pattern: str | None = None
    """Words by which a task asks for it when not granted by name (``DriverSpec.attached_pattern``)."""
    on_request_tools: tuple[str, ...] = ()
    """Tools a process model gets only when its task asks for them (``DriverSpec.on_request_tools``)."""
    on_request_pattern: str | None = None
    server_epoch: str | None = None
    """Names the server process serving it now (``DirectoryEntry.server_epoch``); None: unknown."""
    host: str = ""
    """The host process that serves it (:meth:`DeviceHosting.host_of`); empty: its own. The kernel
    reads the notices of every device on one host with one request."""

    @property
    def grantable(self) -> bool:
        """Whether a process can be given this device now."""
        return self.url is not None and self.status in ("healthy", "starting")
