"""A task file's world on simulators, served in this process and restarted for every task.

:func:`bench_world` resolves the file's devices against the installed drivers, the way
``rosaos.toml`` devices are resolved, always on the ``sim`` backend. :class:`SimDevices` is the
:class:`~rosaos.devices.hosting.DeviceHosting` the benchmark gives the kernel: instead of one host
subprocess per device (``rosaos up``), each simulator is served over streamable HTTP by a task in
this process, so restarting all of them between tasks takes milliseconds and no state leaks
from one task to the next. Workers still reach them over MCP HTTP with a bearer token, exactly
as in ``rosaos up``.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import secrets
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from rosaos.bench.tasks import TaskFile
from rosaos.config import ConfigError, DeviceConfig, RosaosConfig
from rosaos.devices.client import DeviceClient
from rosaos.devices.run_files import DeviceStatus
from rosaos.devices.serve import open_device, serve_http
from rosaos.devices.supervisor import DirectoryEntry, SafeStopOutcome, StatusListener
from rosaos.devices.world import DeviceInstance, World, build_world
from rosaos.drivers import DeviceError
from rosaos.plugins import DriverRegistry

log = logging.getLogger(__name__)

STATE_TIMEOUT = 10.0
"""Seconds one ``get_state`` may take before the device counts as unreadable."""


@dataclass(frozen=True)
class BenchWorld:
    """A task file's devices as a :class:`World`, and the ones that cannot be served, with why."""

    world: World
    """Every device whose driver is installed (placeholders too: the kernel lists them, as in ``rosaos up``)."""
    unavailable: dict[str, str]
    """Device name → why it is not served: ``driver 'reachy' not implemented``, ``... not installed``."""
    invalid: dict[str, str]
    """Device name → why the driver refused its settings (a task-file problem)."""
    sim_settings: dict[str, dict[str, Any]]
    """Device name → its sim-only settings (``sim`` minus what went to the driver's settings)."""

    def simulator_state(self, name: str, state: Mapping[str, Any]) -> dict[str, Any]:
        """The ``sim`` table device ``name`` starts from: its sim-only settings, then ``state``."""
        return {**self.sim_settings.get(name, {}), **state}


def bench_world(task_file: TaskFile, registry: DriverRegistry) -> BenchWorld:
    """Resolve a task file's world on sim backends.

    A ``sim`` key that the driver's settings model declares is a setting, not simulator state:
    ``sim: {profile: turtlebot4}`` of a ros device becomes ``profile = "turtlebot4"``, as the
    README's "a ros instance picks its profile in its settings" says. Everything else in ``sim``,
    and the ``state``, is the simulator's initial state.
    """
    instances: dict[str, DeviceInstance] = {}
    unavailable: dict[str, str] = {}
    invalid: dict[str, str] = {}
    sim_settings: dict[str, dict[str, Any]] = {}
    for name, device in task_file.world.items():
        info = registry.drivers.get(device.driver)
        if info is None:
            installed = ", ".join(registry.names) or "none"
            unavailable[name] = f"driver {device.driver!r} not installed (installed: {installed})"
            continue
        if not info.spec.implemented:
            unavailable[name] = f"driver {device.driver!r} not implemented"
        settings = {key: value for key, value in device.sim.items() if key in info.spec.settings.model_fields}
        sim = {key: value for key, value in device.sim.items() if key not in settings}
        sim_settings[name] = sim
        config = DeviceConfig(
            driver=device.driver,
            backend="sim",
            description=device.description,
            sim={**sim, **device.state},
            **settings,
        )
        try:
            built = build_world(RosaosConfig(devices={name: config}), registry)
        except ConfigError as error:
            invalid[name] = str(error).replace("environment: ", "")
            continue
        instances[name] = built.get(name)
    return BenchWorld(World(instances=instances, source=task_file.path), unavailable, invalid, sim_settings)


@dataclass
class _Served:
    """One simulator being served by a task of its own (so its contexts open and close in one task)."""

    instance: DeviceInstance
    status: DeviceStatus = "starting"
    url: str | None = None
    port: int = 0
    error: str | None = None
    launches: int = 0
    """Servers started for it so far: a restarted one (same URL) knows no earlier session."""
    task: asyncio.Task[None] | None = None
    stop: asyncio.Event = dataclasses.field(default_factory=asyncio.Event)


class SimDevices:
    """Serve a bench world's simulators in this process; implements ``DeviceHosting``.

    ``start``/``stop``/``directory`` are what the kernel calls. :meth:`restart` puts every
    simulator back to a given initial state (a fresh backend, same URL), :meth:`read_states`
    reads them all through ``get_state`` over MCP HTTP.
    """

    def __init__(self, world: World, data_dir: Path) -> None:
        self.world = world
        self.data_dir = data_dir
        self.token = secrets.token_urlsafe(32)
        self._served: dict[str, _Served] = {}
        self.version = 0
        """Bumped whenever a simulator stops or starts (the kernel caches its device list until then)."""
        self.on_status_change: StatusListener | None = None
        """Never called: a simulator in this process does not go down on its own."""

    async def start(self, wait: bool = True) -> None:
        """Serve every implemented instance from the state its ``sim`` table gives (always waits)."""
        for instance in self.world:
            served = _Served(instance)
            if not instance.spec.implemented:
                served.status = "not implemented"
            self._served[instance.name] = served
        self.version += 1
        await self.restart({})

    async def stop(self) -> None:
        """Stop every simulator and close its backend."""
        await asyncio.gather(*(self._halt(served) for served in self._served.values()))

    def directory(self) -> dict[str, DirectoryEntry]:
        """Every instance with its URL and status, as the kernel grants them to workers."""
        return {
            name: DirectoryEntry(
                name=name,
                driver=served.instance.spec.name,
                url=served.url,
                token=self.token,
                status=served.status,
                remote=False,
                error=served.error,
                server_epoch=f"sim-{served.launches}",
            )
            for name, served in self._served.items()
        }

    async def safe_stop_all(self, per_device_timeout: float = 5.0) -> list[SafeStopOutcome]:
        """Call ``safe_stop`` on every served simulator (the kernel's emergency stop)."""

        async def one(name: str, url: str) -> SafeStopOutcome:
            try:
                detail = await DeviceClient(url, self.token, per_device_timeout, name).call("safe_stop")
            except DeviceError as error:
                return SafeStopOutcome(name, False, str(error))
            return SafeStopOutcome(name, True, str(detail))

        served = [(name, s.url) for name, s in self._served.items() if s.url is not None]
        outcomes = list(await asyncio.gather(*(one(name, url) for name, url in served)))
        return outcomes + [
            SafeStopOutcome(name, False, f"not served ({s.status})")
            for name, s in self._served.items()
            if s.url is None
        ]

    async def foreground_settled(self) -> None:
        """Nothing to wait for: :meth:`start` returns once every simulator had its start."""

    def release_background(self) -> None:
        """Nothing to release: every simulator starts in :meth:`start`."""

    async def settle(self, names: Iterable[str]) -> None:
        """Nothing to wait for: :meth:`start` returns once every simulator had its start."""

    def host_of(self, name: str) -> str:
        """Each simulator is its own host."""
        return name

    def failures(self) -> dict[str, str]:
        """Implemented instances that did not start, with the driver's reason."""
        return {name: s.error or s.status for name, s in self._served.items() if s.status == "failed"}

    async def restart(self, sims: Mapping[str, Mapping[str, Any]]) -> None:
        """Restart every implemented simulator; ``sims[name]`` replaces that instance's ``sim`` table."""
        runnable = [s for s in self._served.values() if s.status != "not implemented"]
        await asyncio.gather(*(self._halt(served) for served in runnable))
        for served in runnable:
            if served.instance.name in sims:
                served.instance = dataclasses.replace(served.instance, sim=dict(sims[served.instance.name]))
        await asyncio.gather(*(self._launch(served) for served in runnable))

    async def read_states(self) -> tuple[dict[str, dict[str, Any]], dict[str, str]]:
        """Every served device's ``get_state`` over MCP HTTP; and the ones that failed, with why."""
        served = {name: s for name, s in self._served.items() if s.url is not None}

        async def read(name: str, url: str) -> dict[str, Any] | str:
            try:
                return await DeviceClient(url, self.token, STATE_TIMEOUT, name).get_state()
            except DeviceError as error:
                return str(error)

        answers = await asyncio.gather(*(read(name, s.url or "") for name, s in served.items()))
        states = {name: a for name, a in zip(served, answers, strict=True) if isinstance(a, dict)}
        errors = {name: a for name, a in zip(served, answers, strict=True) if isinstance(a, str)}
        return states, errors

    async def _launch(self, served: _Served) -> None:
        served.stop = asyncio.Event()
        served.launches += 1
        ready: asyncio.Future[str] = asyncio.get_running_loop().create_future()
        served.task = asyncio.create_task(
            self._serve(served, ready), name=f"bench device {served.instance.name}"
        )
        try:
            served.url = await ready
        except DeviceError as error:
            served.status, served.url, served.error = "failed", None, str(error)
            self.version += 1
            log.warning("%s: cannot start its simulator: %s", served.instance.name, error)
            return
        served.status, served.error = "healthy", None
        served.port = urlsplit(served.url).port or 0
        self.version += 1

    async def _serve(self, served: _Served, ready: asyncio.Future[str]) -> None:
        try:
            async with contextlib.AsyncExitStack() as stack:
                opened = await stack.enter_async_context(open_device(served.instance, self.data_dir))
                try:  # the previous port first, so the URL survives restarts
                    http = await stack.enter_async_context(
                        serve_http(opened.server, self.token, port=served.port)
                    )
                except DeviceError:
                    if not served.port:
                        raise
                    http = await stack.enter_async_context(serve_http(opened.server, self.token, port=0))
                ready.set_result(http.url)
                await served.stop.wait()
        except Exception as error:  # one simulator's failure is reported, never fatal to the run
            if not ready.done():
                ready.set_exception(error if isinstance(error, DeviceError) else DeviceError(_reason(error)))
            else:
                log.warning("%s: simulator stopped: %s", served.instance.name, _reason(error))

    async def _halt(self, served: _Served) -> None:
        task, served.task = served.task, None
        if task is None:
            return
        served.stop.set()
        served.url = None
        if served.status != "failed":
            served.status = "stopped"
        self.version += 1
        with contextlib.suppress(Exception):
            await task


def _reason(error: BaseException) -> str:
    return f"{type(error).__name__}: {error}"
