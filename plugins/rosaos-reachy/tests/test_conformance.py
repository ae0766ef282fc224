"""The rosaOS conformance kit, run against the ``reachy`` driver with the SDK's daemon in simulation.

The kit serves the device exactly as ``rosaos up`` does: the ``sim`` backend, which starts
``reachy-mini-daemon`` (MuJoCo, or the mockup where MuJoCo cannot run), over HTTP on loopback.
"""

from rosaos.testing import DriverConformance


class TestReachyDriver(DriverConformance):
    driver = "reachy"
    # The bench's initial state (../shared/bench/tasks/robots.yaml), with the whole head pose:
    # get_state must echo every key exactly.
    sim_state = {
        "head": {"x": 0, "y": 0, "z": 0, "roll": 0, "pitch": 0, "yaw": 0},
        "antennas": [0, 0],
        "body_yaw": 0,
        "awake": True,
        "last_spoken": "",
    }
    settings = {"audio_output": "file"}  # never play sound on the developer's speakers
    out_of_range_call = ("look", {"yaw": 61})
