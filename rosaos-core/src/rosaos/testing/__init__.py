"""The rosaOS driver conformance kit: a pytest suite every driver package runs against itself.

Install ``rosaos[testing]`` and write one class in your driver's tests::

    from rosaos.testing import DriverConformance

    class TestMyDriver(DriverConformance):
        driver = "my_driver"

:class:`RunningDevice` and :func:`run_device` serve an instance over HTTP for your own tests.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rosaos.testing.conformance import DriverConformance
    from rosaos.testing.device_runner import RunningDevice, build_instance, load_all_drivers, run_device

__all__ = ["DriverConformance", "RunningDevice", "build_instance", "load_all_drivers", "run_device"]

# Imported on first use: pytest loads this package (the pytest11 plugin lives in it) in every
# session of an environment that has rosaos[testing], and fastmcp takes seconds to import.
_HOMES = {
    "DriverConformance": "rosaos.testing.conformance",
    "RunningDevice": "rosaos.testing.device_runner",
    "build_instance": "rosaos.testing.device_runner",
    "load_all_drivers": "rosaos.testing.device_runner",
    "run_device": "rosaos.testing.device_runner",
}


def __getattr__(name: str) -> Any:
    if name in _HOMES:
        return getattr(importlib.import_module(_HOMES[name]), name)
    raise AttributeError(f"module 'rosaos.testing' has no attribute {name!r}")
