"""``rosaos ready``: wait until the running kernel is ready, for scripts that start ``rosaos up``.

``rosaos up`` prints its banner before its devices and its worker pool are up (a hundred lamps take
seconds), so a command sent at once waits inside the kernel. A script or a test that wants "up and
warm" runs ``rosaos up &`` and then ``rosaos ready``, which polls ``GET /health`` until it says
``ready`` (every device has had its first start and the pool is warm). It also waits for a kernel
that is still starting, so it can follow ``rosaos up &`` at once.
"""

from __future__ import annotations

import asyncio
import json
import sys
import time
from pathlib import Path
from typing import Any

from rosaos.cli.up_command import EXIT_CONFIG
from rosaos.config import ConfigError, load_config
from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable

POLL_SECONDS = 0.2
EXIT_NOT_READY = 1


def ready_command(config_path: Path | None, url: str | None, timeout: float, json_output: bool) -> int:
    """Wait up to ``timeout`` s; 0 once ready, 1 when not (saying what still starts), 2 for a bad config."""
    try:
        config = load_config(config_path)
    except ConfigError as error:
        print(f"rosaos ready: {error}", file=sys.stderr)
        return EXIT_CONFIG
    health, problem = asyncio.run(_wait(lambda: KernelClient.from_config(config, url=url), timeout))
    if json_output:
        print(json.dumps(health if health is not None else {"ready": False, "error": problem}, indent=2))
    if health is not None and health["ready"]:
        if not json_output:
            print(f"rosaOS is ready (up {health['uptime_seconds']:.1f} s)")
        return 0
    if not json_output:
        print(f"rosaos ready: not ready after {timeout:g} s: {problem}", file=sys.stderr)
    return EXIT_NOT_READY


async def _wait(client: Any, timeout: float) -> tuple[dict[str, Any] | None, str]:
    """The last health seen (None if the kernel never answered) and what was still missing."""
    deadline = time.monotonic() + timeout
    health: dict[str, Any] | None = None
    problem = "no answer from the kernel"
    while True:
        try:
            async with client() as kernel:
                health = await kernel.health()
            if health["ready"]:
                return health, ""
            problem = _missing(health)
            if health["pool"] == "failed":  # it will not get better: `rosaos up` says why and exits
                return health, problem
        except KernelUnavailable as error:
            problem = str(error)
        if time.monotonic() >= deadline:
            return health, problem
        await asyncio.sleep(POLL_SECONDS)


def _missing(health: dict[str, Any]) -> str:
    parts = []
    if health["pool"] != "warm":
        parts.append(f"the worker pool is {health['pool']}")
    if health["devices_starting"]:
        names = health.get("starting") or []
        parts.append(f"{health['devices_starting']} device(s) still starting {', '.join(names)}".rstrip())
    return "; ".join(parts) or "not ready"
