"""How long ``rosaos up`` takes to be ready again after a crash: SIGKILL, restart, ``GET /health``.

The lamps are served by the benchmark process (as ``tests/lamp_rack.py`` serves them), so they
outlive every kernel; only the tapo driver is loaded. Each round starts ``rosaos up``, times the
banner, ``ready`` (devices started, pool warm) and the first command's device call, then kills the
kernel with SIGKILL. The first round starts a fresh fork server; every later one adopts the one
the killed kernel left (``rosaos.processes.fork_parking``), unless ``--no-park``: then each round
has a data directory of its own, so nothing can be adopted (the cost of a restart before). Prints
a table; asserts nothing.

    .venv/bin/python benchmarks/restart.py --rounds 5
    .venv/bin/python benchmarks/restart.py --rounds 5 --no-park
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests/ is imported as a namespace package: its helpers import relatively

from tests.e2e_support import start_kernel  # noqa: E402
from tests.lamp_rack import LampRack  # noqa: E402

TOKEN = "bench-token"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--lamps", type=int, default=6)
    parser.add_argument("--no-park", action="store_true", help="a fresh data directory each round")
    options = parser.parse_args()
    os.environ["ROSAOS_DRIVERS"] = "tapo"
    home = Path(tempfile.mkdtemp(prefix="rosaos-restart-"))
    rack = LampRack(home, [f"lamp_{k}" for k in range(options.lamps)], TOKEN, tool="set_brightness").start()
    rows = []
    try:
        for round_ in range(options.rounds):
            data = home / (f"data-{round_}" if options.no_park else "data")
            config = home / "rosaos.toml"
            config.write_text(
                f'data_dir = "{data}"\n[kernel]\npool_size = 1\n'
                + "".join(
                    f'[devices.{name}]\ndriver = "tapo"\nurl = "{url}"\ntoken = "{TOKEN}"\ndescription = "Lamp"\n'
                    for name, url in rack.urls.items()
                )
            )
            began = time.monotonic()
            kernel = start_kernel(config, ready=False)
            banner = time.monotonic() - began
            kernel.wait_ready()
            ready = time.monotonic() - began
            calls = sum(rack.counts.values())
            with kernel.api() as api:
                api.post("/chat", json={"text": f"set lamp 0 to {10 + round_} percent"}).raise_for_status()
            while sum(rack.counts.values()) == calls and time.monotonic() - began < 300:
                time.sleep(0.01)
            command = time.monotonic() - began
            kernel.kill()
            rows.append((banner, ready, command))
            print(
                f"round {round_ + 1}: banner {banner:.1f} s, ready {ready:.1f} s, first command {command:.1f} s"
            )
    finally:
        rack.close()
    load = os.getloadavg()[0]
    later = rows[1:] or rows
    print(
        "\n| rounds | park | load | first start: banner / ready / command s | restarts (median): banner / ready / command s |"
    )
    print("|---|---|---|---|---|")
    first = rows[0]
    median = [statistics.median(row[i] for row in later) for i in range(3)]
    print(
        f"| {options.rounds} | {'no' if options.no_park else 'yes'} | {load:.1f} | "
        f"{first[0]:.1f} / {first[1]:.1f} / {first[2]:.1f} | {median[0]:.1f} / {median[1]:.1f} / {median[2]:.1f} |"
    )


if __name__ == "__main__":
    main()
