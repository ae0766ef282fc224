"""Running ``rosaos voice`` as its own process against a test kernel, as a user would."""

from __future__ import annotations

import asyncio
import json
import os
import sys
from pathlib import Path
from typing import Any

from rosaos.kernel.runtime import Kernel


async def rosaos_voice(
    kernel: Kernel, wav: Path, timeout: float = 120
) -> tuple[int, list[dict[str, Any]], str]:
    """Run ``rosaos voice --wav FILE --url URL --json`` as its own process, as a user would."""
    env = {**os.environ, "ROSAOS_DATA_DIR": str(kernel.data_dir)}
    env.pop("ROSAOS_CONFIG", None)
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "rosaos.cli",
        "voice",
        "--wav",
        str(wav),
        "--url",
        kernel.url,
        "--json",
        env=env,
        cwd=wav.parent,  # no rosaos.toml there: the defaults, offline
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    out, err = await asyncio.wait_for(process.communicate(), timeout=timeout)
    lines = [json.loads(line) for line in out.decode().splitlines() if line.startswith("{")]
    assert process.returncode is not None
    return process.returncode, lines, err.decode()
