"""Shared helpers for the device hosting tests: a tiny in-test driver, worlds, polling, the CLI.

The tiny driver is registered directly (``load_drivers(extra_plugins=...)``), so in-process tests
do not depend on any installed driver. Anything that crosses a process (device hosts, the CLI)
needs an entry-point driver and uses the Tapo simulator.
"""

from __future__ import annotations

import asyncio
import os
import socket
import sys
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Annotated, Any

import pytest
from fastmcp import FastMCP
from pydantic import Field, SecretStr
from typer.testing import CliRunner

from rosaos import hookimpl
from rosaos.cli import app
from rosaos.config import DeviceConfig, RosaosConfig
from rosaos.devices.run_files import DeviceStatus, RunFile, run_file_path
from rosaos.devices.supervisor import DeviceSupervisor
from rosaos.devices.world import World, build_world
from rosaos.drivers import DeviceBackend, DeviceContext, DeviceError, DeviceSettings, DriverSpec
from rosaos.plugins import DriverRegistry, load_drivers

ROSAOS = Path(sys.executable).parent / "rosaos"
"""The console script of this venv (for the tests that need the CLI as a process of its own)."""


class TinySettings(DeviceSettings):
    secret: SecretStr | None = None


class TinyLamp(DeviceBackend):
    simulated = True

    def __init__(self, ctx: DeviceContext) -> None:
        self.on = bool(ctx.sim.get("on", False))


def tiny_server(ctx: DeviceContext, lamp: TinyLamp) -> FastMCP:
    server = FastMCP(ctx.instance)

    @server.tool(annotations={"readOnlyHint": True})
    def get_state() -> dict[str, Any]:
        """Whether the lamp is on."""
        return {"on": lamp.on}

    @server.tool(annotations={"readOnlyHint": False, "idempotentHint": True})
    def switch(on: bool) -> dict[str, Any]:
        """Turn the lamp on or off."""
        lamp.on = on
        return {"on": lamp.on}

    @server.tool(annotations={"readOnlyHint": True})
    async def slow(seconds: Annotated[float, Field(ge=0, le=30)]) -> str:
        """Answer after ``seconds``."""
        await asyncio.sleep(seconds)
        return "done"

    @server.tool(annotations={"readOnlyHint": True})
    def broken() -> str:
        """Always fails, the way a device that lost power does."""
        raise DeviceError("the lamp does not answer: check that it has power")

    return server


TINY = DriverSpec(
    name="tiny",
    title="Tiny lamp",
    description="A tiny test lamp that can be switched on and off.",
    concurrency="shared",
    prompt="You control a tiny lamp.",
    settings=TinySettings,
    server=tiny_server,
    backends={"sim": TinyLamp},
    demo={},
)

PLACEHOLDER = TINY.model_copy(
    update={"name": "someday", "title": "Someday robot", "implemented": False, "demo": {}}
)


def plugin(*specs: DriverSpec) -> ModuleType:
    """A plugin module registering ``specs``, as an installed package would."""
    module = ModuleType("devices_test_plugin")

    def register_drivers(register: Callable[[DriverSpec], None]) -> None:
        for spec in specs:
            register(spec)

    module.register_drivers = hookimpl(register_drivers)  # type: ignore[attr-defined]
    return module


def drivers_for_tests(*, with_tapo: bool = False) -> DriverRegistry:
    """The tiny and placeholder drivers, plus the installed ``tapo`` when asked."""
    allow = {"test_drivers", "tapo"} if with_tapo else {"test_drivers"}
    return load_drivers(allow=allow, extra_plugins={"test_drivers": plugin(TINY, PLACEHOLDER)})


def world_of(registry: DriverRegistry, data_dir: Path, **devices: dict[str, Any]) -> World:
    """A world with exactly ``devices`` (name -> ``[devices.NAME]`` table)."""
    config = RosaosConfig(
        data_dir=data_dir, devices={name: DeviceConfig(**table) for name, table in devices.items()}
    )
    return build_world(config, registry)


def tapo_installed() -> bool:
    return "tapo" in load_drivers(allow={"tapo"}).names


requires_tapo = pytest.mark.skipif(
    not tapo_installed(), reason="needs the rosaos-tapo driver installed (entry point 'tapo')"
)


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def closed_port_url() -> str:
    """A loopback MCP URL where nothing listens."""
    return f"http://127.0.0.1:{free_port()}/mcp"


async def eventually(check: Callable[[], Awaitable[bool] | bool], within: float = 60.0) -> None:
    """Poll ``check`` until it is true; fail after ``within`` seconds (a deadline, not a sleep)."""
    deadline = time.monotonic() + within
    while True:
        result = check()
        if isinstance(result, Awaitable):
            result = await result
        if result:
            return
        if time.monotonic() > deadline:
            raise AssertionError(f"condition not met within {within} s")
        await asyncio.sleep(0.05)


class HealthWitness:
    """A supervisor's ``on_status_change``: each change, and at each "healthy" report what the
    run file then says of that instance's host pid.

    The supervisor writes a host's pid before it calls the host's instances healthy, so whoever
    hears "healthy" finds the serving process in the file. Read at the moment of the report, so
    the check waits for nothing and cannot pass by luck of timing.
    """

    def __init__(self, supervisor: DeviceSupervisor) -> None:
        self.supervisor = supervisor
        self.changes: list[tuple[str, DeviceStatus, DeviceStatus]] = []
        self.healthy: list[tuple[str, str | None, str | None]] = []
        """``(instance, "pid-N" from the run file, the reported host's server_epoch "pid-M")``."""

    def __call__(self, name: str, old: DeviceStatus, new: DeviceStatus, error: str | None) -> None:
        self.changes.append((name, old, new))
        if new == "healthy":
            epoch = self.supervisor.directory()[name].server_epoch
            self.healthy.append((name, self._recorded(name), epoch))

    def _recorded(self, name: str) -> str | None:
        try:
            runtime = RunFile.model_validate_json(run_file_path(self.supervisor.data_dir).read_text())
        except FileNotFoundError:
            return None
        entry = runtime.devices.get(name)
        return None if entry is None or entry.pid is None else f"pid-{entry.pid}"

    def reported_before_recorded(self) -> list[tuple[str, str | None, str | None]]:
        """The "healthy" reports made while the run file lacked that host's pid (should be none)."""
        return [report for report in self.healthy if report[1] != report[2]]


def pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def write_config(path: Path, data_dir: Path, body: str) -> Path:
    """A rosaos.toml with ``data_dir`` set, so nothing touches the user's home."""
    path.write_text(f'data_dir = "{data_dir}"\n\n{body}', encoding="utf-8")
    return path


@dataclass(frozen=True)
class CliRun:
    """What a ``rosaos`` command returned and printed."""

    returncode: int
    stdout: str
    stderr: str


def rosaos(*args: str, env: dict[str, str] | None = None) -> CliRun:
    """Run a ``rosaos`` command in this process with typer's ``CliRunner``; ``env`` adds to the
    (test-isolated) environment. These tests check what a command prints and returns, which needs
    no process of its own (the ``served`` fixture and the pty tests start real ones)."""
    result = CliRunner().invoke(app, list(args), env=env)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return CliRun(result.exit_code, result.stdout, result.stderr)
