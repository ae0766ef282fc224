"""The rosaOS conformance kit, run against the ``spotify`` driver's simulator."""

from rosaos.testing import DriverConformance


class TestSpotifyDriver(DriverConformance):
    driver = "spotify"
    # The bench's initial state (../shared/bench/tasks/home.yaml): get_state must echo every key.
    sim_state = {"is_playing": False, "volume": 40, "track": None, "shuffle": False, "repeat": "off"}
    out_of_range_call = ("set_volume", {"volume": 101})
