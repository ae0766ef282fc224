"""``rosaos-ros-sim``: run the rosbridge simulator on its own, e.g. to try a rosbridge client."""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import secrets
import sys
from pathlib import Path

from rosaos_ros.profiles import ProfileError, builtin_profiles, load_profile
from rosaos_ros.sim.simulator import Simulator, SimulatorError


def main(argv: list[str] | None = None) -> int:
    """Parse the command line and serve until interrupted."""
    parser = argparse.ArgumentParser(
        prog="rosaos-ros-sim", description="A simulated ROS 2 robot behind a rosbridge v2 WebSocket server."
    )
    parser.add_argument(
        "--profile", default="turtlebot4", help=f"robot profile: {', '.join(builtin_profiles())}"
    )
    parser.add_argument(
        "--profile-file", type=Path, help="a profile YAML file of your own (overrides --profile)"
    )
    parser.add_argument("--host", default="127.0.0.1", help="address to listen on (default: loopback only)")
    parser.add_argument(
        "--port", type=int, default=9090, help="port to listen on (rosbridge's default: 9090)"
    )
    parser.add_argument("--namespace", default="", help="put every name under this namespace, e.g. /robot1")
    parser.add_argument(
        "--token",
        help="require 'Authorization: Bearer TOKEN' (or ?token=TOKEN) from clients (default: a random "
        "one, printed at start)",
    )
    parser.add_argument(
        "--no-token", action="store_true", help="accept clients without a token (anything local can drive)"
    )
    parser.add_argument(
        "--allow-origin",
        action="append",
        default=[],
        metavar="ORIGIN",
        help="a web page origin allowed to connect, e.g. http://localhost:8080 (default: none; repeatable)",
    )
    parser.add_argument(
        "--state", default="{}", help='initial state as JSON, e.g. \'{"x": 1, "docked": false}\''
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log every connection")
    options = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if options.verbose else logging.WARNING, format="%(message)s")
    try:
        state = json.loads(options.state)
        profile = load_profile(options.profile, path=options.profile_file).namespaced(options.namespace)
        token = None if options.no_token else (options.token or secrets.token_urlsafe(24))
        simulator = Simulator(
            profile, state, host=options.host, port=options.port, token=token, origins=options.allow_origin
        )
    except (ProfileError, SimulatorError, ValueError) as error:
        print(f"rosaos-ros-sim: {error}", file=sys.stderr)
        return 2

    async def serve() -> None:
        await simulator.start()
        print(f"rosbridge simulator ({profile.name}) listening on {simulator.url}", flush=True)
        if token is not None and not options.token:
            print(f"token (send 'Authorization: Bearer TOKEN' or ?token=TOKEN): {token}", flush=True)
        try:
            await asyncio.Event().wait()
        finally:
            await simulator.stop()

    try:
        asyncio.run(serve())
    except SimulatorError as error:
        print(f"rosaos-ros-sim: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
