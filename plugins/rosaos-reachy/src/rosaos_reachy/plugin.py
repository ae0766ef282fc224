"""The ``reachy`` driver: what it declares to rosaOS. A placeholder until the driver lands.

Registered under the ``rosaos.drivers`` entry point as ``reachy`` (see ``pyproject.toml``).
``implemented=False`` keeps it listed but never served; the concurrency, demo instance and
name are the real ones, so configurations written today keep working.
"""

from __future__ import annotations

from collections.abc import Callable

from rosaos import hookimpl
from rosaos.drivers import DemoInstance, DriverSpec, read_packaged_text
from rosaos_reachy.backend import sim_backend
from rosaos_reachy.server import build_server

SPEC = DriverSpec(
    name="reachy",
    title="Pollen Robotics Reachy Mini",
    description=(
        "Not implemented yet — see the Reachy Mini driver issue. "
        "The Reachy Mini desktop robot, rosaOS's voice terminal: speak to the user, move its head and "
        "antennas, and look through its camera."
    ),
    concurrency="shared",
    always_attached=True,  # the user interface: every process can speak to the user
    prompt=read_packaged_text(__file__, "prompt.md"),
    server=build_server,
    backends={"sim": sim_backend},
    demo={"reachy": DemoInstance(description="The Reachy Mini on the desk (placeholder: not served yet)")},
    implemented=False,
)


@hookimpl
def register_drivers(register: Callable[[DriverSpec], None]) -> None:
    """Register the ``reachy`` driver (a placeholder)."""
    register(SPEC)
