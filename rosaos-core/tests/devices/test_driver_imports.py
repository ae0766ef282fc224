"""The kernel reads every installed driver's declaration, never its backend.

A driver's ``plugin.py`` is imported by every process that lists drivers: the kernel, the CLI,
each device host. Its backend and tools import the device's SDK (the Reachy SDK with OpenCV and
NumPy, python-kasa with aiohttp, spotipy with requests): tens of MiB and seconds of start-up in a
kernel that never talks to a device itself. So the factories import them when called, in the
device host only (issue 26, part 8).
"""

from __future__ import annotations

import json
import subprocess
import sys

SDKS = ("cv2", "numpy", "reachy_mini", "kasa", "aiohttp", "spotipy", "requests", "mujoco")

PROBE = """
import json, sys
import rosaos.kernel.runtime
from rosaos.plugins import load_drivers
registry = load_drivers()
loaded = sorted({name.split(".")[0] for name in sys.modules} & set(json.loads(sys.argv[1])))
print(json.dumps({"drivers": sorted(registry.names), "loaded": loaded}))
"""


def test_the_kernel_loads_every_driver_without_importing_a_device_sdk() -> None:
    run = subprocess.run(
        [sys.executable, "-P", "-c", PROBE, json.dumps(SDKS)], capture_output=True, text=True, timeout=120
    )
    assert run.returncode == 0, run.stderr
    seen = json.loads(run.stdout.strip().splitlines()[-1])
    assert {"reachy", "ros", "spotify", "tapo"} <= set(seen["drivers"])  # the plugins of this repo
    assert seen["loaded"] == [], f"imported by the kernel for nothing: {seen['loaded']}"
