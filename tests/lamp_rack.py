"""Simulated lamps served over HTTP from the test process, so they outlive a kernel killed with SIGKILL.

Each lamp is a real ``tapo`` device server (:func:`rosaos.devices.serve.open_device` and
:func:`~rosaos.devices.serve.serve_http`) on its own loopback port, run on an event loop in a
thread of the test. Every call of a tool that changes a lamp is counted at the server, which is
where "ran at most once" can be seen whatever happened to the kernel and its workers.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import threading
from collections import Counter
from pathlib import Path
from typing import Any

from fastmcp.server.middleware import CallNext, Middleware, MiddlewareContext

from rosaos.config import load_config
from rosaos.devices.serve import open_device, serve_http
from rosaos.devices.world import build_world
from rosaos.plugins import load_drivers


class CallCounter(Middleware):
    """Counts the calls of ``tool`` on one lamp into shared counters: by lamp, and by lamp and arguments."""

    def __init__(self, lamp: str, tool: str, counts: Counter[str], calls: Counter[tuple[str, str]]) -> None:
        self.lamp, self.tool, self.counts, self.calls = lamp, tool, counts, calls

    async def on_call_tool(self, context: MiddlewareContext[Any], call_next: CallNext[Any, Any]) -> Any:
        if getattr(context.message, "name", "") == self.tool:
            self.counts[self.lamp] += 1
            arguments = getattr(context.message, "arguments", None) or {}
            self.calls[self.lamp, json.dumps(arguments, sort_keys=True)] += 1
        return await call_next(context)


class LampRack:
    """``names`` lamps (all off), served until :meth:`close`; ``urls`` by name, ``counts`` of ``tool``
    by lamp, and ``calls`` of it by lamp and JSON arguments (which command it was)."""

    def __init__(self, home: Path, names: list[str], token: str, tool: str = "toggle") -> None:
        self.names, self.token, self.tool = names, token, tool
        self.urls: dict[str, str] = {}
        self.counts: Counter[str] = Counter()
        self.calls: Counter[tuple[str, str]] = Counter()
        self._home = home
        self._loop = asyncio.new_event_loop()
        self._stop: asyncio.Event | None = None
        self._ready = threading.Event()
        self._failure: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="lamp-rack", daemon=True)

    def start(self) -> LampRack:
        self._thread.start()
        if not self._ready.wait(120) or self._failure is not None:
            raise RuntimeError(f"the lamps did not start: {self._failure}")
        return self

    def close(self) -> None:
        if self._stop is not None:
            self._loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(30)

    def _run(self) -> None:
        try:
            self._loop.run_until_complete(self._serve())
        except BaseException as failure:  # reported by start()
            self._failure = failure
            self._ready.set()

    async def _serve(self) -> None:
        self._stop = asyncio.Event()
        config_file = self._home / "lamps.toml"
        config_file.write_text(
            f'data_dir = "{self._home / "lamp-data"}"\n'
            + "".join(
                f'[devices.{name}]\ndriver = "tapo"\ndescription = "Ceiling light in the {name.split("_")[0]}"\n'
                "sim = { on = false }\n"
                for name in self.names
            )
        )
        config = load_config(config_file)
        world = build_world(config, load_drivers())
        async with contextlib.AsyncExitStack() as stack:
            for name in self.names:
                device = await stack.enter_async_context(open_device(world.instances[name], config.data_dir))
                device.server.add_middleware(CallCounter(name, self.tool, self.counts, self.calls))
                served = await stack.enter_async_context(serve_http(device.server, self.token))
                self.urls[name] = served.url
            self._ready.set()
            await self._stop.wait()
