"""The rosaOS conformance kit, run against the ``reachy`` driver.

The driver is a placeholder (``implemented=False`` in its spec), so the kit checks the
declaration and skips every server check with "driver not implemented yet".
"""

from rosaos.testing import DriverConformance


class TestReachyDriver(DriverConformance):
    driver = "reachy"
