"""The rosaOS conformance kit, run against the ``ros`` driver on its simulator (served over HTTP)."""

from rosaos.testing import DriverConformance


class TestRosDriver(DriverConformance):
    driver = "ros"
