"""``rosaos open``: a fresh one-time login link for the web page of the running kernel.

The link printed by ``rosaos up`` works once and for ten minutes. This asks the running kernel of
the same data directory for a new one (``POST /login-codes`` with the token in the data directory),
prints it, and with ``--browser`` opens it in the default browser.
"""

from __future__ import annotations

import asyncio
import json
import sys
import webbrowser
from pathlib import Path
from typing import Any

from rosaos.config import ConfigError, load_config
from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable

EXIT_UNAVAILABLE = 2


def open_command(config_path: Path | None, url: str | None, browser: bool, json_output: bool) -> int:
    """Mint a login link; print it (or its JSON), and open it in a browser if asked."""

    async def mint() -> dict[str, Any]:
        async with KernelClient.from_config(load_config(config_path), url=url) as client:
            link: dict[str, Any] = await client.request("POST", "/login-codes")
            return link

    try:
        link = asyncio.run(mint())
    except (KernelUnavailable, ConfigError) as error:
        print(f"rosaos open: {error}", file=sys.stderr)
        return EXIT_UNAVAILABLE
    opened = False
    if browser:
        # webbrowser returns False when no browser could be started (a server with no display).
        opened = webbrowser.open(link["url"], new=2)
    if json_output:
        print(json.dumps({**link, "opened": opened}, indent=2))
        return 0
    minutes = max(1, round(link["expires_in"] / 60))
    print(f"{link['url']}   (one-time login link, valid {minutes} minutes)")
    if browser and not opened:
        print("rosaos open: no browser could be started here; open the link above yourself", file=sys.stderr)
    return 0
