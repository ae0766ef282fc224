"""Health checks: reach one instance where it lives and call its ``get_state`` tool.

Shared by ``rosaos devices list`` and ``rosaos devices check``. An instance is checked

- ``served``: at the URL where ``rosaos up`` or ``rosaos serve-device`` on this machine serves it;
- ``remote``: at its configured URL;
- ``in-process``: when nobody serves it, by starting it inside this process for the check.

Start-up and the answer have separate budgets (:class:`CheckBudget`): a simulator that needs 20 s
to boot on a busy machine is slow, not unhealthy, while a started device must answer promptly.
An instance that ``rosaos up`` is still starting is waited for, within the start-up budget, and
never started a second time here.

Instances of one driver start one at a time in this process. ``rosaos up`` gives every instance
a process of its own, so a driver need not cope with two instances starting at once in one
process, and some do not: rosaos-ros shares one roslibpy connection loop per process, and two
concurrent connects can race for it.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from rosaos.auth import load_or_create_token
from rosaos.devices.client import DeviceClient
from rosaos.devices.host import START_TIMEOUT
from rosaos.devices.run_files import RunFileEntry, devices_not_ready, served_devices
from rosaos.devices.serve import OpenDevice, open_device
from rosaos.devices.world import DeviceInstance
from rosaos.drivers import DeviceError

Via = Literal["served", "remote", "in-process"]
Phase = Literal["queued", "starting", "waiting for rosaos up", "asking", "closing", "done"]
"""Where one check stands, for progress: ``queued`` waits for another instance of its driver to start."""

POLL_INTERVAL = 0.2
"""Seconds between looks at the run files while ``rosaos up`` starts an instance."""


@dataclass(frozen=True)
class CheckBudget:
    """How long a check may wait: for the instance to start, then for ``get_state`` to answer."""

    answer: float
    """Seconds ``get_state`` may take (``--timeout``)."""
    start: float = START_TIMEOUT
    """Seconds an instance may take to start, here or in ``rosaos up`` (``--start-timeout``)."""


@dataclass(frozen=True)
class Route:
    """Where an instance is checked, as the run files tell it before the check."""

    via: Via
    url: str | None
    entry: RunFileEntry | None = None
    """What ``rosaos up``/``serve-device`` recorded, when it serves the instance or is starting it."""

    @property
    def starting_elsewhere(self) -> bool:
        """``rosaos up`` hosts the instance but does not serve it yet."""
        return self.via == "served" and self.url is None


@dataclass
class CheckResult:
    """The outcome of one check: the ``get_state`` answer, or the reason there is none."""

    route: Route
    state: dict[str, Any] | None = None
    error: str | None = None
    still_starting: bool = False
    """``rosaos up`` had not finished starting it within the start-up budget: slow, not broken."""

    @property
    def ok(self) -> bool:
        return self.error is None


def find_routes(instances: list[DeviceInstance], data_dir: Path) -> dict[str, Route]:
    """Where each instance would be checked, from the run files of this machine."""
    served = served_devices(data_dir)
    pending = devices_not_ready(data_dir)
    return {instance.name: _route(instance, served, pending) for instance in instances}


def _route(
    instance: DeviceInstance, served: dict[str, RunFileEntry], pending: dict[str, RunFileEntry]
) -> Route:
    entry = served.get(instance.name)
    if entry is not None and entry.url:
        return Route("served", entry.url, entry)
    if instance.url is not None:
        return Route("remote", instance.url)
    if instance.name in pending:
        return Route("served", None, pending[instance.name])
    return Route("in-process", None)


class _StillStarting(DeviceError):
    """``rosaos up`` is still starting the instance when the start-up budget runs out."""


def _no_report(name: str, phase: Phase) -> None:
    pass


class HealthCheck:
    """Checks instances concurrently within a :class:`CheckBudget`, reporting each one's phase.

    ``report(name, phase)`` is called as a check moves on (for a progress display).
    """

    def __init__(
        self, data_dir: Path, budget: CheckBudget, report: Callable[[str, Phase], None] = _no_report
    ) -> None:
        self.data_dir = data_dir
        self.budget = budget
        self.report = report
        self._starting: defaultdict[str, asyncio.Lock] = defaultdict(asyncio.Lock)
        """One lock per driver: its instances start one at a time (see the module docstring)."""

    async def check(self, instance: DeviceInstance, route: Route) -> CheckResult:
        """Check ``instance`` along ``route``; never raises for the device's own failures."""
        result = CheckResult(route)
        try:
            if route.via == "in-process":
                result.state = await self._check_here(instance)
            else:
                if route.starting_elsewhere:
                    assert route.entry is not None
                    entry = await self._wait_for_rosaos_up(instance.name, route.entry)
                    result.route = Route("served", entry.url, entry)
                result.state = await self._ask_over_http(instance, result.route.url)
        except _StillStarting as error:
            result.error, result.still_starting = str(error), True
        except DeviceError as error:
            result.error = str(error)
        finally:
            self.report(instance.name, "done")
        return result

    async def _ask_over_http(self, instance: DeviceInstance, url: str | None) -> dict[str, Any]:
        assert url is not None
        self.report(instance.name, "asking")
        token = instance.token or await asyncio.to_thread(load_or_create_token, self.data_dir)
        return await DeviceClient(url, token, self.budget.answer, instance.name).get_state()

    async def _check_here(self, instance: DeviceInstance) -> dict[str, Any]:
        """Start the backend in this process, call get_state through an in-memory client, close it."""
        name = instance.name
        try:
            async with contextlib.AsyncExitStack() as opened:
                lock = self._starting[instance.spec.name]
                if lock.locked():
                    self.report(name, "queued")
                async with lock:
                    device = await self._start_here(instance, opened)
                self.report(name, "asking")
                state = await DeviceClient.in_process(device.server, self.budget.answer, name).get_state()
                self.report(name, "closing")
                return state
        except DeviceError:
            raise
        except Exception as error:  # driver code: report it as the device's error, not a traceback
            raise DeviceError(f"{name}: {type(error).__name__}: {error}") from None

    async def _start_here(self, instance: DeviceInstance, opened: contextlib.AsyncExitStack) -> OpenDevice:
        self.report(instance.name, "starting")
        seconds = self.budget.start
        try:
            async with asyncio.timeout(seconds) as deadline:
                return await opened.enter_async_context(open_device(instance, self.data_dir))
        except TimeoutError:
            if not deadline.expired():  # the driver's own timeout: its message says more
                raise
            raise DeviceError(
                f"{instance.name} did not finish starting within {seconds:g} s; a slow simulator or "
                "a busy machine may need more (--start-timeout)"
            ) from None

    async def _wait_for_rosaos_up(self, name: str, entry: RunFileEntry) -> RunFileEntry:
        """Wait, within the start-up budget, until ``rosaos up`` serves ``name``; its served entry."""
        self.report(name, "waiting for rosaos up")
        seconds = self.budget.start
        try:
            async with asyncio.timeout(seconds):
                while True:
                    if entry.status == "failed":
                        reason = entry.error or "no reason recorded"
                        raise DeviceError(f"rosaos up cannot start {name}: {reason} (it keeps retrying)")
                    await asyncio.sleep(POLL_INTERVAL)
                    served = (await asyncio.to_thread(served_devices, self.data_dir)).get(name)
                    if served is not None and served.url:
                        return served
                    pending = (await asyncio.to_thread(devices_not_ready, self.data_dir)).get(name)
                    if pending is None:
                        raise DeviceError(f"{name}: rosaos up stopped while it was starting it")
                    entry = pending
        except TimeoutError:
            raise _StillStarting(
                f"rosaos up is still starting {name} after {seconds:g} s (status {entry.status}); "
                "wait, or allow longer with --start-timeout"
            ) from None
