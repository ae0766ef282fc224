"""The rosaOS driver conformance kit: a pytest suite every driver package runs against itself.

Install ``rosaos[testing]`` and write one class in your driver's tests::

    from rosaos.testing import DriverConformance

    class TestMyDriver(DriverConformance):
        driver = "my_driver"

For your own tests: :class:`RunningDevice` and :func:`run_device` serve an instance over HTTP;
:func:`open_sim_device` drives your server in memory on the ``sim`` backend (a :class:`SimDevice`);
:class:`IntentProbe` checks which tool call your ``intents.yaml`` makes of a sentence.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rosaos.testing.conformance import DriverConformance
    from rosaos.testing.device_runner import RunningDevice, build_instance, load_all_drivers, run_device
    from rosaos.testing.intents import IntentMatch, IntentProbe
    from rosaos.testing.sim_device import SimDevice, open_sim_device

__all__ = [
    "DriverConformance",
    "IntentMatch",
    "IntentProbe",
    "RunningDevice",
    "SimDevice",
    "build_instance",
    "load_all_drivers",
    "open_sim_device",
    "run_device",
]

# Imported on first use: pytest loads this package (the pytest11 plugin lives in it) in every
# session of an environment that has rosaos[testing], and fastmcp takes seconds to import.
_HOMES = {
    "DriverConformance": "rosaos.testing.conformance",
    "IntentMatch": "rosaos.testing.intents",
    "IntentProbe": "rosaos.testing.intents",
    "RunningDevice": "rosaos.testing.device_runner",
    "SimDevice": "rosaos.testing.sim_device",
    "build_instance": "rosaos.testing.device_runner",
    "load_all_drivers": "rosaos.testing.device_runner",
    "open_sim_device": "rosaos.testing.sim_device",
    "run_device": "rosaos.testing.device_runner",
}


def __getattr__(name: str) -> Any:
    if name in _HOMES:
        return getattr(importlib.import_module(_HOMES[name]), name)
    raise AttributeError(f"module 'rosaos.testing' has no attribute {name!r}")
