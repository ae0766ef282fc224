"""The running kernel: devices, event store, worker pool, kernel agent and HTTP API, wired together.

:class:`Kernel` is what ``rosaos up`` runs and what integration tests start on loopback. It
implements the HTTP API's :class:`~rosaos.kernel.api.schemas.KernelRuntime`.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import socket
import sqlite3
from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Protocol

import httpx
import uvicorn
from pydantic import ValidationError
from pydantic_ai.models import Model

from rosaos.auth import bound_hosts, load_or_create_token
from rosaos.config import MapOrigin, RosaosConfig
from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.devices.run_files import write_atomic
from rosaos.devices.serve import bind_socket
from rosaos.devices.state_cache import DeviceStateCache
from rosaos.devices.supervisor import DeviceSupervisor, DirectoryEntry, SafeStopOutcome
from rosaos.devices.world import World
from rosaos.drivers import DeviceError
from rosaos.events.callback import WorkerCallback, callback_idempotency_key
from rosaos.events.plan import Plan
from rosaos.events.types import DeviceNoticeEvent, Event, WorkerCallbackEvent
from rosaos.kernel.activity import ActivityLog
from rosaos.kernel.agent import build_kernel_agent, kernel_prompt
from rosaos.kernel.api.app import create_app
from rosaos.kernel.api.kernel_client import kernel_file, running_kernel_url
from rosaos.kernel.api.login_codes import LoginCodes, login_url
from rosaos.kernel.api.schemas import (
    DeviceSafeStop,
    DeviceView,
    EmergencyStopReport,
    EmergencyStopState,
    Understanding,
)
from rosaos.kernel.confirmation_chat import answer_from_chat, ask_people, record_confirmation
from rosaos.kernel.confirmations import ConfirmationDesk
from rosaos.kernel.database import StoreClosedError
from rosaos.kernel.device_status import DeviceStatusUpdates
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.host_latch import HostLatches
from rosaos.kernel.launch_cause import CurrentEvent, LaunchCause
from rosaos.kernel.loop import KernelLoop
from rosaos.kernel.notices import NoticeWatcher
from rosaos.kernel.orphans import LiveProcesses, recover_orphans
from rosaos.kernel.pending_stops import PendingStops, StopUndelivered
from rosaos.kernel.stop_tools import add_stop_tools
from rosaos.kernel.stopping import Stopper
from rosaos.kernel.timer_tools import add_timer_tools
from rosaos.kernel.timers import TimerBook
from rosaos.kernel.tools import build_kernel_tools
from rosaos.kernel.updates import UpdateStream
from rosaos.memory.memory_tools import add_memory_tools, memory_summary
from rosaos.memory.sightings import SightingLog
from rosaos.memory.store import MemoryStore
from rosaos.models.defaults import KernelModels, kernel_models
from rosaos.models.select import ModelSpec
from rosaos.processes.confirming import ConfirmRule, confirm_rule
from rosaos.processes.manager import EmergencyStop, LaunchRefused, ProcessInfo, ProcessManager
from rosaos.processes.pool import WorkerPool
from rosaos.processes.prompts import base_process_prompt

log = logging.getLogger(__name__)

EVENTS_FILE = "kernel.sqlite3"
EMERGENCY_STOP_KEY = "emergency_stop"
"""The event store's key for the latched emergency stop (``EmergencyStop`` as JSON, or null)."""


class KernelError(Exception):
    """The kernel cannot start; the message says why and what to do."""


class DeviceHosting(Protocol):
    """Where the kernel's devices come from. :class:`DeviceSupervisor` (host processes) in
    ``rosaos up``; the task benchmark serves its simulators in-process instead."""

    async def start(self) -> None: ...

    async def stop(self) -> None: ...

    def directory(self) -> dict[str, DirectoryEntry]: ...

    async def safe_stop_all(self) -> list[SafeStopOutcome]: ...


class Kernel:
    """One rosaOS instance: ``await kernel.start()``, then ``await kernel.stop()``."""

    def __init__(
        self,
        config: RosaosConfig,
        world: World,
        *,
        kernel_model: Model | None = None,
        process_model: ModelSpec | None = None,
        worker_env: Mapping[str, str] | None = None,
        devices: DeviceHosting | None = None,
    ) -> None:
        self.config = config
        self.world = world
        self.data_dir = config.data_dir
        self._models: KernelModels = kernel_models(config, world, override=kernel_model)
        self._process_model = process_model or self._models.process
        self._worker_env = dict(worker_env) if worker_env else None
        self._hosting = devices
        self._ended_published: set[int] = set()
        self._tasks: list[asyncio.Task[Any]] = []
        self._server: uvicorn.Server | None = None
        self._started = False
        self.login_codes = LoginCodes()
        self.url = ""
        self.status_updates: DeviceStatusUpdates | None = None
        self._endpoints: tuple[int, dict[str, DeviceEndpoint]] | None = None
        """``endpoints()`` as of the supervisor's ``version``."""
        """Publishes devices going down and back (None when the devices are hosted elsewhere)."""

    # --- KernelRuntime ---------------------------------------------------------------------------

    @property
    def events(self) -> EventStore:
        return self._store

    @property
    def updates(self) -> UpdateStream:
        return self._updates

    @property
    def activity(self) -> ActivityLog:
        return self._activity

    @property
    def token(self) -> str:
        return self._token

    @property
    def model_description(self) -> str:
        return self._models.description

    async def understand(self, text: str) -> Understanding:
        local = self._models.local
        if local is None:
            return Understanding(text=text, complete=False, kind="no_engine")
        # Matching a sentence that does not fit takes up to a few hundred ms: not on the loop.
        result = await asyncio.to_thread(local.match, text)
        return Understanding(text=text, complete=result.is_exact, kind=result.kind)

    @property
    def model_notice(self) -> str | None:
        return self._models.notice

    async def processes(self, include_ended: bool = False) -> Sequence[ProcessInfo]:
        return self.manager.list(include_ended=include_ended)

    async def terminate(self, process_id: int) -> ProcessInfo:
        return await self.manager.terminate(process_id)

    async def launch(self, task: str, devices: list[str], plan: Plan | None = None) -> ProcessInfo:
        """A process the page launched (a card control), recorded and announced as the kernel's own are."""
        info = await self.manager.launch(task, devices, before_start=self._launching_uncaused, plan=plan)
        data = {"process_id": info.id, "devices": info.devices, "state": info.state}
        await self._updates.publish(
            "process_launched", f"process {info.id} launched with {', '.join(info.devices)}", data
        )
        return info

    async def devices(self) -> Sequence[DeviceView]:
        await self.states.wanted()
        running = self.manager.list()
        return [
            DeviceView(
                name=endpoint.name,
                driver=endpoint.driver,
                concurrency=endpoint.concurrency,
                backend=self.world.instances[endpoint.name].backend,
                status=endpoint.status,
                url=endpoint.url,
                state=self.states.get(endpoint.name),
                description=endpoint.description,
                held_by=[p.id for p in running if endpoint.name in p.devices],
                card=self._card(endpoint.name),
                map_origin=self._map_origin(endpoint.name),
            )
            for endpoint in self.endpoints().values()
        ]

    def _map_origin(self, name: str) -> MapOrigin | None:
        device = self.config.devices.get(name)
        return device.map_origin if device is not None else None

    def _card(self, name: str) -> dict[str, Any] | None:
        """The card its driver declares, as the web page reads it; None draws a key list."""
        card = self.world.instances[name].spec.card
        return card.view() if card else None

    async def worker_callback_recorded(self, event_id: int, callback: WorkerCallback) -> None:
        self.manager.record_callback(callback)
        await self._activity.record(event_id, callback.process_id, callback.receipts)
        self.sightings.record_receipts(callback.receipts)  # the people its robots saw
        if callback.process_id not in self._ended_published:
            self._ended_published.add(callback.process_id)
            text = f"process {callback.process_id} ended: {callback.status}"
            if callback.error:
                text += f" ({callback.error})"
            await self._updates.publish(
                "process_ended", text, callback.model_dump(mode="json"), event_id=event_id
            )
        # Forgotten only once its end is on the updates stream: a kill before this line leaves the
        # record, and the restart publishes the committed callback (kernel/orphans.py).
        await self._live.ended(callback.process_id)

    async def emergency_stop(self, reason: str) -> EmergencyStopReport:
        """Terminate every process, call every device's safe_stop, and latch until reset.

        The latch is in memory at once, and saved in the event store while the devices stop: the
        stop never waits on the disk, and the answer comes once the latch survives a restart.
        """
        stopped = await self.manager.latch_emergency_stop(reason)
        latch = self.manager.emergency_stop
        assert latch is not None
        outcomes, saved, untold = await asyncio.gather(
            self.supervisor.safe_stop_all(), self._save_latch(latch), self._host_latches.push(True, reason)
        )
        await self._pending_stops.note(outcomes)  # an unreachable device is stopped when it is back
        report = EmergencyStopReport(
            latched=True,
            reason=latch.reason,
            time=latch.time,
            terminated=[info.id for info in stopped],
            devices=[DeviceSafeStop(name=o.instance, ok=o.ok, detail=o.detail) for o in outcomes],
            saved=saved,
            untold_hosts=untold,
        )
        await self._updates.publish("error", f"EMERGENCY STOP: {reason}", report.model_dump(mode="json"))
        return report

    async def reset_emergency_stop(self) -> EmergencyStopState:
        """Unlatch the emergency stop (a person decided it is safe).

        The latch is cleared on disk first: if that fails, the stop stays latched and this raises.
        """
        latch = self.manager.emergency_stop
        if latch is None:  # nothing to reset: say nothing on the updates stream
            return self.emergency_stop_state()
        await self._store.set_value(EMERGENCY_STOP_KEY, None)
        if self.manager.emergency_stop is latch:  # not if a new stop came while the disk was busy
            self.manager.reset_emergency_stop()
            await self._host_latches.push(False)
            await self._updates.publish("notice", "emergency stop reset: processes may run again", {})
        return self.emergency_stop_state()

    def emergency_stop_state(self) -> EmergencyStopState:
        latch = self.manager.emergency_stop
        untold = list(self._host_latches.untold)
        if latch is None:
            return EmergencyStopState(latched=False, untold_hosts=untold)
        return EmergencyStopState(latched=True, reason=latch.reason, time=latch.time, untold_hosts=untold)

    async def _save_latch(self, latch: EmergencyStop) -> bool:
        """Save the latch for the next start; False (and a log entry) if the store failed."""
        try:
            await self._store.set_value(EMERGENCY_STOP_KEY, latch.model_dump(mode="json"))
        except (sqlite3.Error, StoreClosedError):
            log.exception("the emergency stop is latched, but could not be saved: a restart would forget it")
            return False
        return True

    # --- devices -----------------------------------------------------------------------------------

    async def devices_settled(self) -> None:
        """Wait until every device, the background-start ones too, has had its first start attempt.

        ``start`` returns without waiting for those (the Reachy simulator boots for seconds).
        """
        if isinstance(self.supervisor, DeviceSupervisor):
            await self.supervisor.settle(self.world.instances)

    def endpoints(self) -> dict[str, DeviceEndpoint]:
        """The world's devices as the process manager grants them.

        Built again only when the supervisor's ``version`` says a device changed: a burst of
        events then costs no walk over a hundred devices each (callers must not mutate it)."""
        version = getattr(self.supervisor, "version", None)
        if version is not None and self._endpoints is not None and self._endpoints[0] == version:
            return self._endpoints[1]
        endpoints = {}
        for name, entry in self.supervisor.directory().items():
            instance = self.world.instances[name]
            spec = instance.spec
            endpoints[name] = DeviceEndpoint(
                name=name,
                driver=spec.name,
                concurrency=spec.concurrency,
                always_attached=spec.always_attached,
                description=instance.description,
                prompt=spec.prompt,
                url=entry.url,
                token=entry.token or self._token,
                status=entry.status,
                confirm=self._confirm_rule(name),
                attached_tools=tuple(spec.attached_tools),
                attached_prompt=spec.attached_prompt,
            )
        if version is not None:
            self._endpoints = (version, endpoints)
        return endpoints

    def _confirm_rule(self, name: str) -> ConfirmRule:
        instance, configured = self.world.instances[name], self.config.devices.get(name)
        own = configured.confirm if configured is not None else None
        return confirm_rule(own, self.config.confirm, instance.backend, instance.spec.confirm_on_real)

    # --- lifecycle ---------------------------------------------------------------------------------

    async def start(self, host: str | None = None, port: int | None = None) -> str:
        """Start devices, the event store, the pool, the loop and the API; return the API's base URL."""
        host = host or self.config.kernel.host
        port = self.config.kernel.port if port is None else port
        self._token = load_or_create_token(self.data_dir)  # creates the data directory, owner-only
        sock = await _bind_or_explain(host, port, self._token)
        self.url = _base_url(sock)
        try:
            await self._start_parts(sock)
        except BaseException:
            await self.stop()
            sock.close()
            raise
        self._started = True
        write_atomic(kernel_file(self.data_dir), json.dumps({"url": self.url, "pid": os.getpid()}))
        return self.url

    async def _start_parts(self, sock: socket.socket) -> None:
        self._store = await EventStore.open(self.data_dir / EVENTS_FILE)
        self._updates = await UpdateStream.open(self._store.database)
        self._activity = await ActivityLog.open(self._store.database)
        self.confirmations = ConfirmationDesk(
            self.config.kernel.confirm_timeout,
            lambda item: ask_people(self._updates, self.endpoints(), item),
            record=lambda item: record_confirmation(self._activity, self._updates, item),
        )
        self._live = LiveProcesses(self._store)
        self.timers = await TimerBook.open(self._store, self._updates.publish_event)
        # A device that boots in the background (the Reachy simulator: seconds of CPU) waits until
        # the other devices and the workers are up: on two cores it would otherwise delay them.
        self.supervisor = self._hosting or DeviceSupervisor(
            self.world, self.data_dir, self._token, defer_background=True
        )
        if isinstance(self.supervisor, DeviceSupervisor):
            self.status_updates = DeviceStatusUpdates(self._updates, self.supervisor.host_of)
            self.supervisor.on_status_change = self.status_updates.changed
        kernel = self.config.kernel
        pool = WorkerPool(
            size=kernel.pool_size,
            env=self._worker_env,
            fork_server=kernel.fork_server,
            max_workers=kernel.max_workers,
        )
        self.manager = ProcessManager(
            devices=self.endpoints,
            model=self._process_model,
            base_prompt=base_process_prompt(self.config.kernel.process_prompt),
            job_timeout=self.config.kernel.job_timeout,
            request_limit=self.config.kernel.request_limit,
            callback_url=f"{self.url}/event",
            callback_token=self._token,
            pool=pool,
            on_ended=self._process_ended,
            first_process_id=await self._store.next_process_id(),
            emergency_stop=await _stored_emergency_stop(self._store),
        )
        # Devices (a robot simulator takes seconds to boot) and the warm workers (seconds of
        # imports each) start side by side; neither needs the other until the first event.
        try:
            async with asyncio.TaskGroup() as group:
                group.create_task(self.supervisor.start(), name="start devices")
                group.create_task(self.manager.start(), name="start worker pool")
        except BaseExceptionGroup as failed:
            raise failed.exceptions[0] from None
        # Before the loop can grant anything: devices a dead kernel's processes held get safe_stop,
        # so one still starting in the background (the Reachy simulator) is waited for first.
        if isinstance(self.supervisor, DeviceSupervisor):
            self.supervisor.release_background()
            await self.supervisor.settle({name for p in await self._live.left() for name in p.devices})
        # Opened before orphan recovery: a callback it republishes records its sightings.
        self.memory = MemoryStore.open(self.data_dir)
        self.sightings = SightingLog(self.memory, self.config.memory.sightings_days)
        self._pending_stops = PendingStops(
            self._store,
            self.supervisor.directory,
            lambda text, data: self._updates.publish("notice", text, data),
        )
        await self._pending_stops.deliver()  # owed by the last run: a device that is back is stopped now
        self._host_latches = HostLatches(self.supervisor.directory)
        if self.manager.emergency_stop is not None:  # latched before the restart: so are the hosts
            await self._host_latches.push(True, self.manager.emergency_stop.reason)
        stops = await recover_orphans(
            self._live,
            self._store,
            self.supervisor.directory(),
            self._callback_committed,
            remember=self.manager.remember,
        )
        await self._pending_stops.note(stops)
        self.states = DeviceStateCache(self.endpoints)
        current = CurrentEvent()
        tools = build_kernel_tools(
            self.manager,
            self.endpoints,
            current=current,
            before_start=self._launching,
            launched_before=self._live.launched_for,
        )
        add_timer_tools(tools, self.timers)
        add_memory_tools(tools, self.memory, self.endpoints, self._launch, self.sightings)
        if self._models.local is not None:
            self._models.local.memory = self.memory
        self.stopper = Stopper(
            self.manager, self.endpoints, lambda name: self.world.instances[name].spec.halts
        )
        add_stop_tools(tools, self.stopper, self.manager, self.endpoints)
        agent = build_kernel_agent(self._models.kernel, tools)
        self.loop = KernelLoop(
            self._store,
            self._updates,
            agent,
            instructions=lambda: (
                kernel_prompt(self.endpoints().values(), self.config.kernel.kernel_prompt)
                + memory_summary(self.memory)
            ),
            model=self._model_for_event,
            history_budget=self.config.kernel.history_messages,
            current=current,
            history_chars=self.config.kernel.history_chars,
            relay_reports=self.config.kernel.relay_reports,
        )
        self.loop.before = lambda event: answer_from_chat(self.confirmations, event)
        app = create_app(
            self,
            allowed_hosts=[*kernel.allow_hosts, *bound_hosts(sock.getsockname()[0])],
            images_dir=self.data_dir / "images",
        )
        config = uvicorn.Config(app, log_level="warning", lifespan="on", timeout_graceful_shutdown=3)
        self._server = uvicorn.Server(config)
        self._tasks.append(asyncio.create_task(self._server.serve(sockets=[sock]), name="kernel api"))
        while not self._server.started:
            if self._tasks[-1].done():
                self._tasks[-1].result()
                raise KernelError("the kernel API stopped during start-up")
            await asyncio.sleep(0.01)
        self._tasks.append(asyncio.create_task(self.states.run(), name="device states"))
        self.notices = NoticeWatcher(self.endpoints, self._enqueue_notice)
        self._tasks.append(asyncio.create_task(self.notices.run(), name="device notices"))
        self._tasks.append(asyncio.create_task(self._pending_stops.run(), name="pending safe stops"))
        self._tasks.append(asyncio.create_task(self._host_latches.run(), name="host latches"))
        self._tasks.append(asyncio.create_task(self._run_loop(), name="kernel loop"))
        # Timers that fell due while the kernel was down fire now, once, and say they are late.
        self._tasks.append(asyncio.create_task(self.timers.run(), name="timers"))

    def _model_for_event(self, event: Event) -> Model | None:
        return self._models.for_event(event)

    async def _run_loop(self) -> None:
        try:
            await self.loop.run_forever()
        except asyncio.CancelledError:
            raise
        except Exception:  # the loop must not die silently: say so where the user looks
            log.exception("the kernel loop stopped")
            await self._updates.publish("error", "the kernel loop stopped; see the console log")
            raise

    async def stop(self) -> None:
        """Shut everything down: no orphan processes; unhandled events stay queued for next time."""
        for task in reversed(self._tasks):
            if task.get_name() == "kernel api" and self._server is not None:
                self._server.should_exit = True
            else:
                task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        self._tasks.clear()
        if hasattr(self, "manager"):
            await self.manager.stop()
        if hasattr(self, "supervisor"):
            await self.supervisor.stop()
        if hasattr(self, "_store"):
            await self._store.close()
        if self._started and running_kernel_url(self.data_dir) == self.url:
            kernel_file(self.data_dir).unlink(missing_ok=True)
        self._started = False

    def login_link(self) -> str:
        """A fresh one-time link that logs the web page in."""
        return login_url(self.url + "/", self.login_codes.mint())

    async def _process_ended(self, callback: WorkerCallback, delivered: bool) -> None:
        """The pool saw a process end. If its worker could not post the callback, enqueue it here."""
        if delivered:
            return
        event = WorkerCallbackEvent(
            kind="worker_callback",
            source="kernel",
            payload=callback,
            idempotency_key=callback_idempotency_key(callback.process_id),
        )
        appended = await self._store.append(event)
        if not appended.duplicate:
            await self._updates.publish_event(appended.id, event)
        await self.worker_callback_recorded(appended.id, callback)

    async def _callback_committed(self, event_id: int, event: WorkerCallbackEvent) -> None:
        """A callback the kernel wrote itself (for an orphan): on the updates stream, then recorded."""
        await self._updates.publish_event(event_id, event)
        await self.worker_callback_recorded(event_id, event.payload)

    async def _enqueue_notice(self, event: DeviceNoticeEvent) -> None:
        """A device notice the filter let through: into the queue, and onto the updates stream."""
        appended = await self._store.append(event)
        if not appended.duplicate:
            await self._updates.publish_event(appended.id, event)

    async def _launch(self, task: str, devices: list[str], plan: Plan) -> ProcessInfo:
        """Launch a process as ``launch_process`` does (a memory tool's: drive to a place)."""
        return await self.manager.launch(task, devices, before_start=self._launching_uncaused, plan=plan)

    async def _launching_uncaused(self, info: ProcessInfo) -> None:
        """Before a worker has the job of a launch no event step caused (a card control, a memory
        tool): recorded for orphan recovery all the same."""
        await self._launching(info, None)

    async def _launching(self, info: ProcessInfo, cause: LaunchCause | None) -> None:
        """Before a worker has the job: keep ids unique across restarts, and remember the process
        and its cause until its end is recorded. A crash after this line leaves an orphan record."""
        try:
            await self._pending_stops.before_grant(info.devices)
        except StopUndelivered as owed:
            raise LaunchRefused(str(owed)) from None
        await self._store.note_process_id(info.id)
        await self._live.launched(info, cause)


def _base_url(sock: socket.socket) -> str:
    host, port = sock.getsockname()[:2]
    shown = f"[{host}]" if ":" in host else host
    if host in ("0.0.0.0", "::"):
        shown = "127.0.0.1"
    return f"http://{shown}:{port}"


async def _bind_or_explain(host: str, port: int, token: str) -> socket.socket:
    """Bind the API's port, or say what already runs there."""
    try:
        return bind_socket(host, port)
    except DeviceError:
        pass
    url = f"http://{'127.0.0.1' if host in ('0.0.0.0', '') else host}:{port}"
    with contextlib.suppress(httpx.HTTPError, ValueError):
        async with httpx.AsyncClient(timeout=2) as client:
            health = (await client.get(f"{url}/health")).json()
        if "version" in health:
            raise KernelError(
                f"rosaOS {health['version']} is already running at {url}/ (model: {health.get('model')}); "
                "use `rosaos chat` to talk to it, or stop it first, or start this one with --port"
            )
    raise KernelError(f"port {port} on {host} is in use by another program; start rosaOS with --port N")


async def _stored_emergency_stop(store: EventStore) -> EmergencyStop | None:
    """The emergency stop latched before this start, if any.

    A stored latch this version cannot read stays latched (with a reason saying so): only a
    person may unlatch it.
    """
    stored = await store.get_value(EMERGENCY_STOP_KEY)
    if stored is None:
        return None
    try:
        return EmergencyStop.model_validate(stored)
    except ValidationError:
        return EmergencyStop(
            reason=f"a stored emergency stop could not be read ({json.dumps(stored)[:200]})",
            time=datetime.now(UTC),
        )


def events_path(data_dir: Path) -> Path:
    """Where the kernel keeps its event store."""
    return data_dir / EVENTS_FILE
