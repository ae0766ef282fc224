from rosaos.testing import DriverConformance


class TestTapoDriver(DriverConformance):
    driver = "tapo"
