"""The settings of one ``tapo`` instance: the keys of ``[devices.NAME]`` besides driver, backend and sim."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, SecretStr

from rosaos.drivers import DeviceSettings

Connection = Literal["klap", "discover"]
"""How the real backend finds out the bulb's protocol: assume KLAP (current firmware, plain TCP,
works across subnets) or ask the bulb by UDP discovery (any firmware, same LAN only)."""


class TapoSettings(DeviceSettings):
    """One bulb's settings: the keys of ``[devices.NAME]`` besides driver, backend and sim.

    Only the ``real`` backend uses them; the simulator needs none. The password can come from
    the environment instead of the file: ``ROSAOS_DEVICES__NAME__PASSWORD``.
    """

    host: str | None = Field(default=None, description="IP address or hostname of the bulb.")
    username: str | None = Field(
        default=None, description="Email of the TP-Link cloud account that set the bulb up in the Tapo app."
    )
    password: SecretStr | None = Field(default=None, description="Password of that TP-Link account.")
    timeout: Annotated[float, Field(gt=0, le=120)] = Field(
        default=10.0, description="Seconds one operation (connect, command, read) may take."
    )
    # Not "port": [devices.NAME] port is rosaOS's own, the loopback port of the device server.
    bulb_port: Annotated[int, Field(ge=1, le=65535)] | None = Field(
        default=None, description="The bulb's HTTP port, if not 80 (port forwarding)."
    )
    connection: Connection = Field(
        default="klap",
        description='"klap" (current firmware) or "discover" (ask the bulb by UDP; old firmware, same LAN).',
    )
