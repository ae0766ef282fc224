"""The ``reachy`` backends. None exists yet: the ``sim`` factory says so with a clear error."""

from __future__ import annotations

from rosaos.drivers import DeviceBackend, DeviceContext, DeviceError


def sim_backend(ctx: DeviceContext) -> DeviceBackend:
    """The ``sim`` backend: not written yet, so it refuses with the reason."""
    raise DeviceError(
        f"{ctx.instance}: the Reachy Mini driver is not implemented yet "
        "(see the Reachy Mini driver issue); remove this device from rosaos.toml for now"
    )
