"""Serve the local instances of a world in host processes, keep them alive, and say where they are.

:class:`DeviceSupervisor` is what ``rosaos up`` runs. Every simulated instance of a driver that
does not ask for a process of its own (``DriverSpec.own_process``) is served by one shared device
host (:mod:`rosaos.devices.host_batch`); every other local instance (a real device) gets a host
subprocess of its own (:mod:`rosaos.devices.host`). A simulated instance whose driver starts in
the background (the Reachy, ``DriverSpec.background_start``) joins the running shared host once
:meth:`DeviceSupervisor.release_background` lets it, so its boot holds nothing up.

Liveness is checked per host, not per instance (:mod:`rosaos.devices.liveness`): the host's
heartbeat, a line its event loop writes every second, speaks for all the instances it serves.
A late beat changes nothing; only after several checks without a fresh beat *and* a failed real
call (``get_state`` with a generous timeout, during which no beat came either) is the host
called down and restarted. A host that exits is restarted at once. Restarts
back off exponentially, and a crash restarts the instances of that host and no other. An instance
that cannot start in the shared host is retried in a host of its own. A host that cannot start is
reported (log, status, run file) and retried, never fatal. Placeholder drivers are listed as
``not implemented``; remote instances are only probed, with ``get_state``, and are called
``unreachable`` after several failures in a row.

:meth:`DeviceSupervisor.start` returns once every instance has had its first start attempt,
except those whose driver starts in the background (``DriverSpec.background_start``): they stay
``starting`` until they answer, and :meth:`DeviceSupervisor.settle` waits for them.

The run file ``<data_dir>/run/devices.json`` tells other commands (``rosaos devices list``,
``rosaos devices check``) which instances are being served, and where. It is rewritten when a
status changes, not on every probe. It has a host's pid before that host's instances are
reported healthy: whoever hears "healthy" and reads the file finds the process serving them.
``rosaos serve-device`` records its one instance in ``<data_dir>/run/serve-device/<name>.json``.
"""

from __future__ import annotations

import asyncio
import logging
import os
from collections.abc import Callable, Coroutine, Iterable
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path
from types import TracebackType
from typing import Any
from urllib.parse import urlsplit

from rosaos.auth import token_path
from rosaos.clock import LOOP_CLOCK, Clock, sleep_unless
from rosaos.devices.client import DeviceClient
from rosaos.devices.directory import DirectoryEntry, SafeStopOutcome, safe_stop_entry
from rosaos.devices.host import START_TIMEOUT, HostJob
from rosaos.devices.host_process import HostProcess
from rosaos.devices.liveness import LivenessRule
from rosaos.devices.run_files import (
    DeviceStatus,
    RunFile,
    RunFileEntry,
    now,
    read_runtime_file,
    run_file_path,
    write_atomic,
)
from rosaos.devices.world import DeviceInstance, World
from rosaos.drivers import DeviceError

__all__ = [
    "SHARED_HOST",
    "DeviceSupervisor",
    "DirectoryEntry",
    "SafeStopOutcome",
    "StatusListener",
    "safe_stop_entry",
]

SHARED_HOST = "shared-sims"
"""Name of the shared host's log file (``logs/devices/shared-sims.log``)."""

log = logging.getLogger("rosaos.devices.supervisor")

SAVE_DELAY = 0.05
"""Seconds a run-file write waits for more changes (a shared host reports its instances one by one):
at most twenty writes a second however many instances start, and the file is never far behind."""


StatusListener = Callable[[str, DeviceStatus, DeviceStatus, str | None], None]
"""``(instance, old status, new status, error)``."""


@dataclass
class _Hosted:
    """The supervisor's view of one instance."""

    instance: DeviceInstance
    status: DeviceStatus
    since: datetime = field(default_factory=now)
    url: str | None = None
    error: str | None = None
    host: HostProcess | None = None
    port: int | None = None
    restarts: int = 0
    remote_misses: int = 0
    """Failed ``get_state`` probes in a row, for a remote instance."""
    settled: asyncio.Event = field(default_factory=asyncio.Event)
    """Set after the first start attempt (or first probe, for remote instances)."""

    @property
    def shares_host(self) -> bool:
        """Served with other simulators in the shared host (see the module docstring)."""
        spec = self.instance.spec
        return self.instance.backend == "sim" and not spec.own_process and not self.instance.is_remote


class DeviceSupervisor:
    """Serve the local instances of ``world`` in host subprocesses; probe and restart them.

    Use as ``async with DeviceSupervisor(world, data_dir, token) as supervisor:``. After
    :meth:`start` returns, every instance has had its first start attempt.
    """

    def __init__(
        self,
        world: World,
        data_dir: Path,
        token: str,
        *,
        host: str = "127.0.0.1",
        health_interval: float = 5.0,
        health_timeout: float = 3.0,
        unhealthy_after: int = 3,
        real_call_timeout: float = 20.0,
        backoff_base: float = 0.5,
        backoff_cap: float = 30.0,
        start_timeout: float = START_TIMEOUT,
        stop_grace: float = 5.0,
        defer_background: bool = False,
        clock: Clock = LOOP_CLOCK,
    ) -> None:
        self.world = world
        self.clock = clock
        """What the health checks wait on, ``health_interval`` apart, and what a local host's
        heartbeat is timed on (tests move a :class:`~rosaos.testing.manual_clock.ManualClock`)."""
        self._background_go = asyncio.Event()
        """Background-start instances wait for this: at once, or :meth:`release_background` when
        ``defer_background`` (``rosaos up`` lets the other devices and the workers boot first)."""
        if not defer_background:
            self._background_go.set()
        self.data_dir = data_dir
        self.token = token
        self.host = host
        self.health_interval = health_interval
        self.health_timeout = health_timeout
        self.unhealthy_after = unhealthy_after
        """Missed liveness probes in a row before a real call decides whether a host is down."""
        self.real_call_timeout = real_call_timeout
        self.heartbeat = min(1.0, health_interval / 2)
        """Seconds between a host's heartbeat lines: at least two per check."""
        """Seconds that real call may take: generous, so that a busy machine is not a dead host."""
        self.backoff_base = backoff_base
        self.backoff_cap = backoff_cap
        self.start_timeout = start_timeout
        self.stop_grace = stop_grace
        self._devices: dict[str, _Hosted] = {}
        self._tasks: list[asyncio.Task[None]] = []
        self.version = 0
        """Bumped whenever an instance's status, URL or error changes: the kernel caches its
        device list until then, so an event costs no walk over every device."""
        self.on_status_change: StatusListener | None = None
        """Called as ``(instance, old, new, error)`` whenever an instance's status changes."""
        self._save_lock = asyncio.Lock()
        self._token_file = token_path(data_dir)
        self._owns_runtime_file = False
        self._save_later: asyncio.Task[None] | None = None
        self._saved_pids: dict[str, int | None] = {}
        """Each instance's host pid as the run file last written has it (see :meth:`_record_pids`)."""

    async def __aenter__(self) -> DeviceSupervisor:
        try:
            await self.start()
        except BaseException:
            await self.stop()
            raise
        return self

    async def __aexit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.stop()

    @property
    def runtime_file(self) -> Path:
        return run_file_path(self.data_dir)

    def log_file(self, name: str) -> Path:
        """Where a host's stderr goes: driver output, uvicorn warnings, tracebacks."""
        return self.data_dir / "logs" / "devices" / f"{name}.log"

    async def start(self, wait: bool = True) -> None:
        """Start every local host and probe every remote instance; return once each has settled.

        With ``wait=False`` it returns as soon as the hosts are starting: ``rosaos up`` shows its
        banner then, and each instance becomes grantable as its host reports it (:meth:`settle`
        waits for named ones)."""
        other = await asyncio.to_thread(read_runtime_file, self.data_dir)
        if other is not None and other.supervisor_pid != os.getpid():
            raise DeviceError(
                f"devices in {self.data_dir} are already served by another rosaOS (pid "
                f"{other.supervisor_pid}); stop it first, or use another data_dir"
            )
        self._owns_runtime_file = True
        await asyncio.to_thread(self._prepare_files)
        shared: list[_Hosted] = []
        for instance in self.world:
            if not instance.spec.implemented:
                self._devices[instance.name] = _Hosted(instance, "not implemented")
                continue
            hosted = _Hosted(instance, "starting", port=instance.port)
            self._devices[instance.name] = hosted
            if instance.is_remote:
                self._run(self._watch_remote(hosted), instance.name)
            elif hosted.shares_host:
                shared.append(hosted)
            elif instance.spec.background_start:
                self._run(self._keep_serving([hosted], wait_for=self._background_go), instance.name)
            else:
                self._run(self._keep_serving([hosted]), instance.name)
        if len(shared) == 1:
            self._run(self._keep_serving(shared), shared[0].instance.name)
        elif shared:
            self._run(self._keep_serving(shared), SHARED_HOST)
        # Record "starting" at once: `devices list` and `devices check` then wait for these
        # instances instead of starting second copies while their hosts boot.
        await self._save()
        if not wait:
            return
        await self.foreground_settled()
        await self._save()

    async def foreground_settled(self) -> None:
        """Wait until every instance but the background-start ones has had its first start attempt."""
        await self.settle(
            name
            for name, d in self._devices.items()
            if d.status != "not implemented" and not d.instance.spec.background_start
        )

    def release_background(self) -> None:
        """Let the background-start instances begin (see ``defer_background``)."""
        self._background_go.set()

    async def settle(self, names: Iterable[str]) -> None:
        """Wait until each named instance has had its first start attempt (unknown names: skipped)."""
        await asyncio.gather(*(self._devices[name].settled.wait() for name in names if name in self._devices))

    def _run(self, runner: Coroutine[Any, Any, None], name: str) -> None:
        self._tasks.append(asyncio.create_task(runner, name=f"device {name}"))

    def _prepare_files(self) -> None:
        # Hosts read the token from a file, never from argv (visible in ps) or the environment.
        if not (
            self._token_file.is_file() and self._token_file.read_text(encoding="utf-8").strip() == self.token
        ):
            self._token_file = self.data_dir / "run" / "device-token"
            write_atomic(self._token_file, self.token + "\n")
        self.log_file("any").parent.mkdir(parents=True, exist_ok=True)

    async def stop(self) -> None:
        """Stop watching, terminate every host (and its process group), remove the run file."""
        if self._save_later is not None:
            self._save_later.cancel()
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        self._tasks.clear()
        await self._terminate_group(list(self._devices.values()))
        for hosted in self._devices.values():
            if hosted.status != "not implemented" and not hosted.instance.is_remote:
                self._set(hosted, "stopped", url=None)
        if self._owns_runtime_file:  # never remove the file of another rosaOS we refused to race
            async with self._save_lock:
                await asyncio.to_thread(self.runtime_file.unlink, missing_ok=True)

    def host_of(self, name: str) -> str:
        """Which host serves ``name``: the shared host's name, or the instance's own name."""
        hosted = self._devices.get(name)
        return SHARED_HOST if hosted is not None and hosted.shares_host else name

    def directory(self) -> dict[str, DirectoryEntry]:
        """Every instance with its URL, token and status: what the kernel grants to workers."""
        return {
            name: DirectoryEntry(
                name=name,
                driver=d.instance.spec.name,
                url=d.url,
                token=(d.instance.token or self.token) if d.instance.is_remote else self.token,
                status=d.status,
                remote=d.instance.is_remote,
                error=d.error,
                restarts=d.restarts,
                server_epoch=None if d.instance.is_remote or d.host is None else f"pid-{d.host.pid}",
            )
            for name, d in self._devices.items()
        }

    def last_beat(self, name: str) -> float | None:
        """When the host serving ``name`` last wrote a line (its heartbeat), on :attr:`clock`; None
        while no host runs it. What its health checks judge (:mod:`rosaos.devices.liveness`)."""
        hosted = self._devices.get(name)
        return None if hosted is None or hosted.host is None else hosted.host.last_tick

    async def safe_stop_all(self, per_device_timeout: float = 5.0) -> list[SafeStopOutcome]:
        """Call ``safe_stop`` on every reachable instance at once; failures are reported, not raised."""
        entries = [e for e in self.directory().values() if e.url]
        outcomes = list(await asyncio.gather(*(safe_stop_entry(e, per_device_timeout) for e in entries)))
        # A device that is not served has nothing running to stop: reported, not a failure.
        outcomes += [
            SafeStopOutcome(e.name, True, f"not served ({e.status}): nothing to stop")
            for e in self.directory().values()
            if not e.url
        ]
        return outcomes

    # --- local instances: one host process each, or several in the shared one ------------------

    async def _keep_serving(
        self, group: list[_Hosted], delay: float = 0.0, wait_for: asyncio.Event | None = None
    ) -> None:
        """Start the group's host; when it dies or stops answering, start it again after a backoff."""
        failures = 0
        if wait_for is not None:
            await wait_for.wait()
        await asyncio.sleep(delay)
        while True:
            started = asyncio.get_running_loop().time()
            try:
                later = await self._launch(group)
                for hosted in group:
                    if hosted not in later:
                        hosted.settled.set()
                await self._watch_local(group, later)
            except DeviceError as error:
                for hosted in group:
                    log.warning("%s: cannot start: %s", hosted.instance.name, error)
                    self._set(hosted, "failed", url=None, error=str(error))
            except Exception as error:  # one device's trouble must never take the supervisor down
                log.exception("%s: unexpected error while hosting it", _names(group))
                for hosted in group:
                    self._set(hosted, "failed", url=None, error=f"{type(error).__name__}: {error}")
            await self._terminate_group(group)
            for hosted in group:
                hosted.settled.set()
            await self._save()
            if len(group) > 1 and all(hosted.status == "failed" for hosted in group):
                # The shared host does not start at all: halves find the culprit, a host per
                # instance only in the end. Never one process per instance at once: three
                # hundred hosts starting together would bring the machine to its knees.
                middle = len(group) // 2
                for half in (group[:middle], group[middle:]):
                    self._run(self._keep_serving(half, self.backoff_base), _names(half[:1]))
                return
            lived = asyncio.get_running_loop().time() - started
            # A host that ran for a while earned a fresh start; a crash loop backs off to the cap.
            failures = 1 if lived >= self.backoff_cap else failures + 1
            delay = min(self.backoff_cap, self.backoff_base * 2 ** (failures - 1))
            for hosted in group:
                if hosted.status != "failed":
                    self._set(hosted, "restarting", url=None)
            await self._save()
            log.info("%s: restarting in %.1f s", _names(group), delay)
            await asyncio.sleep(delay)
            for hosted in group:
                hosted.restarts += 1

    async def _launch(self, group: list[_Hosted]) -> list[_Hosted]:
        """Start the group's host process; wait for its ready lines and a first answer to get_state.

        An instance of a shared host that could not start leaves the group for a host of its own.
        Returns the group's background-start instances, which join the running shared host later
        (:meth:`_join_later`), unless the group has nothing else: then it waits for them.
        """
        for hosted in group:
            if hosted.status != "failed":  # a retry of a failed start stays "failed" until it works
                self._set(hosted, "starting", error=hosted.error)
        later = [hosted for hosted in group if hosted.instance.spec.background_start]
        if len(later) == len(group):
            await self._background_go.wait()
            later = []
        now = [hosted for hosted in group if hosted not in later]
        jobs = [self._job(hosted) for hosted in now]
        if len(group) == 1:
            log_file = self.log_file(group[0].instance.name)
            host = await HostProcess.spawn(
                jobs[0], log_file, self.start_timeout, self.stop_grace, clock=self.clock
            )
            host.urls[group[0].instance.name] = host.url
        else:
            log_file = self.log_file(SHARED_HOST)
            arrivals = _Arrivals(self, now)
            try:
                host = await HostProcess.spawn_batch(
                    jobs,
                    log_file,
                    self.start_timeout,
                    self.stop_grace,
                    on_ready=arrivals.ready,
                    clock=self.clock,
                )
            except BaseException:
                await arrivals.close(cancel=True)
                raise
            await arrivals.close()
            if arrivals.answered.is_set():  # the host has answered a real call already
                await self._mark_healthy([hosted for hosted in now if hosted.instance.name in host.urls])
        for hosted in list(now):
            name = hosted.instance.name
            if name in host.errors:
                self._leave_shared_host(group, hosted, f"{host.errors[name]} (log: {log_file})")
                now.remove(hosted)
                continue
            hosted.host, hosted.url = host, host.urls[name]
            hosted.port = urlsplit(hosted.url).port
            log.info("%s: serving at %s (pid %s)", name, hosted.url, host.pid)
        await self._first_answer(now)
        return later

    def _job(self, hosted: _Hosted) -> HostJob:
        return HostJob.for_instance(
            hosted.instance,
            self.data_dir,
            self._token_file,
            self.world.source,
            host=self.host,
            heartbeat=self.heartbeat,
            port=hosted.instance.port or 0,
            preferred_port=None if hosted.instance.port else hosted.port,
        )

    def _leave_shared_host(self, group: list[_Hosted], hosted: _Hosted, error: str) -> None:
        """An instance that cannot start in the shared host is retried in a host of its own."""
        name = hosted.instance.name
        log.warning("%s: cannot start in the shared host: %s", name, error)
        self._set(hosted, "failed", url=None, error=error)
        hosted.settled.set()
        group.remove(hosted)
        self._run(self._keep_serving([hosted], self.backoff_base), name)

    async def _join_later(self, group: list[_Hosted], hosted: _Hosted, host: HostProcess) -> None:
        """Start a background-start instance in the running shared host once it is released.

        The Reachy simulator boots its MuJoCo daemon for seconds: in the shared host it neither
        holds up the banner nor the other instances, and costs no interpreter of its own.
        """
        await self._background_go.wait()
        try:
            url = await host.join(self._job(hosted), self.start_timeout)
        except DeviceError as error:
            self._leave_shared_host(group, hosted, str(error))
            await self._save()
            return
        hosted.host, hosted.url, hosted.port = host, url, urlsplit(url).port
        log.info("%s: serving at %s (pid %s)", hosted.instance.name, url, host.pid)
        await self._first_answer([hosted])
        hosted.settled.set()

    async def _first_answer(self, group: list[_Hosted]) -> None:
        """One ``get_state`` for the whole host (its instances share its process): healthy, or not yet.

        The budget is the start-up one: a host that has just said it serves is slow, not broken,
        when a busy machine delays its first answer."""
        await self._record_pids(group)
        if all(hosted.status == "healthy" for hosted in group):  # answered while the others started
            await self._save()
            return
        error = await self._real_call(group[0], self.start_timeout)
        for hosted in group:
            self._set(hosted, "healthy" if error is None else "unhealthy", error=error)
        await self._save()

    async def _watch_local(self, group: list[_Hosted], later: list[_Hosted]) -> None:
        """Probe the host until it exits, or misses probes and then fails a real call (see the module).

        ``later`` join the host meanwhile (:meth:`_join_later`); a restart starts them again."""
        served = next(hosted for hosted in group if hosted.url is not None)
        host = served.host
        assert host is not None
        exited = asyncio.create_task(host.wait())
        gone = asyncio.Event()
        exited.add_done_callback(lambda _: gone.set())
        joining = [asyncio.create_task(self._join_later(group, hosted, host)) for hosted in later]
        rule = LivenessRule(self.unhealthy_after)
        try:
            while True:
                await sleep_unless(self.clock, self.health_interval, gone)
                if exited.done():
                    error = await host.exit_reason()
                    log.warning("%s: %s", _names(group), error)
                    for hosted in group:
                        self._set(hosted, "restarting", url=None, error=error)
                    return
                verdict = rule.observe(self._beating(host))
                if verdict == "late":
                    log.info("%s: no heartbeat at check %d; not down yet", _names(group), rule.misses)
                    continue
                if verdict == "ask":
                    last_beat = host.last_tick
                    failure = await self._real_call(served, self.real_call_timeout)
                    if failure is not None and host.last_tick == last_beat and not exited.done():
                        log.warning(
                            "%s: no heartbeat for %d checks and get_state failed (%s); restarting the host",
                            _names(group),
                            rule.misses,
                            failure,
                        )
                        for hosted in group:
                            self._set(hosted, "unhealthy", error=failure)
                        await self._save()
                        return
                    rule.real_call_answered()
                await self._mark_healthy([hosted for hosted in group if hosted.url is not None])
        finally:
            exited.cancel()
            for task in joining:
                task.cancel()

    def _beating(self, host: HostProcess) -> bool:
        """The host's one liveness signal: a heartbeat within the last ``health_timeout`` (plus a beat)."""
        return self.clock.now() - host.last_tick <= self.health_timeout + self.heartbeat

    async def _real_call(self, hosted: _Hosted, timeout: float) -> str | None:
        """``get_state`` on one instance: None when it answered, else the error."""
        assert hosted.url is not None
        token = hosted.instance.token or self.token
        try:
            await DeviceClient(hosted.url, token, timeout, hosted.instance.name).get_state()
        except DeviceError as error:
            return str(error)
        return None

    async def _mark_healthy(self, group: list[_Hosted]) -> None:
        changed = [hosted for hosted in group if hosted.status != "healthy"]
        await self._record_pids(changed)
        for hosted in changed:
            self._set(hosted, "healthy", error=None)
        if changed:
            await self._save()

    async def _probe_remote(self, hosted: _Hosted) -> None:
        """One check of a remote instance: ``get_state``; ``unreachable`` after several failures."""
        error = await self._real_call(hosted, self.health_timeout)
        if error is None:
            hosted.remote_misses = 0
            if hosted.status != "healthy":
                self._set(hosted, "healthy", error=None)
            return
        hosted.remote_misses += 1
        first = not hosted.settled.is_set()
        if first or hosted.remote_misses >= self.unhealthy_after:
            self._set(hosted, "unreachable", error=error)

    async def _watch_remote(self, hosted: _Hosted) -> None:
        """Remote instances are someone else's to restart; only report whether they answer."""
        hosted.url = hosted.instance.url
        while True:
            await self._probe_remote(hosted)
            hosted.settled.set()
            await self.clock.sleep(self.health_interval)

    async def _terminate_group(self, group: list[_Hosted]) -> None:
        hosts = {id(hosted.host): hosted.host for hosted in group if hosted.host is not None}
        for hosted in group:
            hosted.host = None
        await asyncio.gather(*(host.stop(self.stop_grace) for host in hosts.values()))

    # --- status and the run file -------------------------------------------------------------

    async def _record_pids(self, group: list[_Hosted]) -> None:
        """Write the run file now if it lacks one of these hosts' pids: before they are called healthy.

        Otherwise a reader told "healthy" (the kernel's status listener, ``rosaos devices list``)
        could find the instance in the file without its process, and a kernel killed between the
        report and the write would leave a serving host that the file does not name (CI runs 21
        and 24: tests read the file in that gap).
        """
        unrecorded = [
            hosted
            for hosted in group
            if hosted.host is not None
            and hosted.url is not None
            and self._saved_pids.get(hosted.instance.name) != hosted.host.pid
        ]
        if unrecorded:
            await self._save()

    def _set(
        self, hosted: _Hosted, status: DeviceStatus, *, error: str | None = None, **changes: Any
    ) -> None:
        old = hosted.status
        self.version += 1
        if status != old:
            hosted.since = now()
        hosted.status = status
        hosted.error = error
        for key, value in changes.items():
            setattr(hosted, key, value)
        if status != old and self.on_status_change is not None:
            self.on_status_change(hosted.instance.name, old, status, error)

    def _save_soon(self) -> None:
        """Rewrite the run file within :data:`SAVE_DELAY` s: one write for a host's many ready lines."""
        if self._save_later is None or self._save_later.done():
            self._save_later = asyncio.create_task(self._save_after(SAVE_DELAY), name="save the run file")

    async def _save_after(self, delay: float) -> None:
        await asyncio.sleep(delay)
        await self._save()

    async def _save(self) -> None:
        async with self._save_lock:
            if not self._tasks:  # stopped (or not started): the file must not reappear
                return
            runtime = RunFile(
                supervisor_pid=os.getpid(),
                devices={
                    name: RunFileEntry(
                        url=d.url,
                        pid=d.host.pid if d.host and d.url else None,
                        status=d.status,
                        since=d.since,
                        error=d.error,
                        restarts=d.restarts,
                    )
                    for name, d in self._devices.items()
                    if d.status != "not implemented" and not d.instance.is_remote
                },
            )
            await asyncio.to_thread(write_atomic, self.runtime_file, runtime.model_dump_json(indent=2))
            self._saved_pids = {name: entry.pid for name, entry in runtime.devices.items()}


class _Arrivals:
    """A shared host's instances, made grantable one by one as their ready lines arrive.

    The first one to arrive gets the host's one real call (``get_state``); once that answered,
    each later instance is healthy as soon as it says it serves and the run file has the host's
    pid: they share the process that just answered, and a hundred more MCP sessions would only
    slow the start down. Ready lines that arrive while the file is written wait for the next write.
    """

    def __init__(self, supervisor: DeviceSupervisor, group: list[_Hosted]) -> None:
        self._supervisor = supervisor
        self._group = {hosted.instance.name: hosted for hosted in group}
        self.answered = asyncio.Event()
        self._asking: asyncio.Task[None] | None = None
        self._arrived: list[_Hosted] = []
        self._announcing: asyncio.Task[None] | None = None

    async def ready(self, host: HostProcess, name: str, url: str) -> None:
        hosted = self._group.get(name)
        if hosted is None:
            return
        hosted.host, hosted.port = host, urlsplit(url).port
        self._supervisor._set(hosted, hosted.status, error=hosted.error, url=url)
        if self._asking is None:
            self._asking = asyncio.create_task(self._ask(hosted), name=f"first answer of {name}")
        if self.answered.is_set():
            self._arrived.append(hosted)
            if self._announcing is None or self._announcing.done():
                self._announcing = asyncio.create_task(self._announce(), name="healthy in the shared host")
        else:
            self._supervisor._save_soon()

    async def _announce(self) -> None:
        """Mark the instances that arrived since the last write healthy (the pid written first)."""
        while self._arrived:
            arrived, self._arrived = self._arrived, []
            await self._supervisor._mark_healthy(arrived)
            for hosted in arrived:
                hosted.settled.set()

    async def _ask(self, hosted: _Hosted) -> None:
        if await self._supervisor._real_call(hosted, self._supervisor.start_timeout) is not None:
            return  # the whole batch gets its real call again once it has started
        self.answered.set()
        served = [
            other for other in self._group.values() if other.url is not None and other.host is hosted.host
        ]
        await self._supervisor._mark_healthy(served)
        for other in served:
            other.settled.set()

    async def close(self, cancel: bool = False) -> None:
        """Wait for the first answer (bounded by the start-up budget), or cancel it (start failed)."""
        if self._asking is None:
            return
        if cancel:
            self._asking.cancel()
            if self._announcing is not None:
                self._announcing.cancel()
        await asyncio.gather(self._asking, return_exceptions=True)
        if self._announcing is not None:  # no ready line comes after the batch has started
            await asyncio.gather(self._announcing, return_exceptions=True)


def _names(group: list[_Hosted]) -> str:
    return ", ".join(hosted.instance.name for hosted in group)
