"""The running kernel: its parts (built once, :mod:`rosaos.kernel.parts`) and its HTTP API.

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
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

import httpx
import uvicorn
from pydantic_ai.models import Model

from rosaos.auth import bound_hosts, load_or_create_token
from rosaos.config import MapOrigin, RosaosConfig
from rosaos.confirmations.confirmation_desk import ConfirmationDesk
from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.devices.hosting import DeviceHosting
from rosaos.devices.run_files import write_atomic
from rosaos.devices.serve import bind_socket
from rosaos.devices.world import World
from rosaos.drivers import DeviceError
from rosaos.events.plan import Plan
from rosaos.fastmcp_spans import spans_off
from rosaos.kernel.activity import ActivityLog
from rosaos.kernel.api.app import create_app
from rosaos.kernel.api.kernel_client import kernel_file, running_kernel_url
from rosaos.kernel.api.login_codes import LoginCodes, login_url
from rosaos.kernel.api.schemas import (
    DeviceView,
    EmergencyStopReport,
    EmergencyStopState,
    Readiness,
    Understanding,
)
from rosaos.kernel.emergency_stop import EMERGENCY_STOP_KEY as EMERGENCY_STOP_KEY
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.intake import Intake
from rosaos.kernel.loop import KernelLoop
from rosaos.kernel.parts import EVENTS_FILE, KernelParts, build_parts
from rosaos.kernel.updates import UpdateStream
from rosaos.memory.sightings import SightingLog
from rosaos.memory.store import MemoryStore
from rosaos.models.defaults import KernelModels, kernel_models
from rosaos.models.select import ModelSpec
from rosaos.notices.notice_watcher import NoticeWatcher
from rosaos.processes.manager import ProcessInfo, ProcessManager
from rosaos.timers.timer_book import TimerBook

log = logging.getLogger(__name__)


class KernelError(Exception):
    """The kernel cannot start; the message says why and what to do."""


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
        self._parts: KernelParts | None = None
        self._shutdown = contextlib.AsyncExitStack()
        """Stops what :func:`build_parts` started, in reverse order (also after a failed start)."""
        self._tasks: list[asyncio.Task[Any]] = []
        self._server: uvicorn.Server | None = None
        self._started = False
        self._token = ""
        self.login_codes = LoginCodes()
        self.url = ""

    @property
    def parts(self) -> KernelParts:
        """The running kernel's parts; only after :meth:`start`."""
        if self._parts is None:
            raise KernelError("the kernel is not running: await kernel.start() first")
        return self._parts

    # --- KernelRuntime ---------------------------------------------------------------------------

    @property
    def events(self) -> EventStore:
        return self.parts.store

    @property
    def intake(self) -> Intake:
        return self.parts.intake

    @property
    def updates(self) -> UpdateStream:
        return self.parts.updates

    @property
    def activity(self) -> ActivityLog:
        return self.parts.activity

    @property
    def confirmations(self) -> ConfirmationDesk:
        return self.parts.confirmations

    @property
    def timers(self) -> TimerBook:
        return self.parts.timers

    @property
    def manager(self) -> ProcessManager:
        return self.parts.manager

    @property
    def loop(self) -> KernelLoop:
        return self.parts.loop

    @property
    def memory(self) -> MemoryStore:
        return self.parts.memory

    @property
    def sightings(self) -> SightingLog:
        return self.parts.sightings

    @property
    def notices(self) -> NoticeWatcher:
        return self.parts.notices

    @property
    def supervisor(self) -> DeviceHosting:
        """Whatever serves the devices (a ``DeviceSupervisor`` in ``rosaos up``)."""
        return self.parts.hosting

    @property
    def token(self) -> str:
        return self._token

    @property
    def model_description(self) -> str:
        return self._models.description

    @property
    def model_notice(self) -> str | None:
        return self._models.notice

    async def understand(self, text: str) -> Understanding:
        local = self._models.local
        if local is None:
            return Understanding(text=text, complete=False, kind="no_engine")
        # Matching a sentence that does not fit takes up to a few hundred ms: not on the loop.
        result = await asyncio.to_thread(local.match, text)
        instances = self.world.instances
        moves = result.is_exact and result.starts_motion(
            lambda name: instances[name].spec.halts if name in instances else ()
        )
        return Understanding(text=text, complete=result.is_exact, kind=result.kind, moves=moves)

    def readiness(self) -> Readiness:
        """Devices still starting and the pool's warm-up: what "ready" after the banner waits for."""
        starting = sorted(
            name for name, entry in self.supervisor.directory().items() if entry.status == "starting"
        )
        warming = self.manager.warming
        pool: Literal["warming", "warm", "failed"] = "warm"
        if warming is not None and not warming.done():
            pool = "warming"
        elif warming is not None and (warming.cancelled() or warming.exception() is not None):
            pool = "failed"
        return Readiness(
            ready=pool == "warm" and not starting,
            pool=pool,
            devices_starting=len(starting),
            starting=starting,
        )

    async def processes(self, include_ended: bool = False) -> Sequence[ProcessInfo]:
        return self.manager.list(include_ended=include_ended)

    async def terminate(self, process_id: int) -> ProcessInfo:
        return await self.manager.terminate(process_id)

    async def launch(self, task: str, devices: list[str], plan: Plan | None = None) -> ProcessInfo:
        """A process the page launched (a card control), recorded and announced as the kernel's own are."""
        info = await self.manager.launch(
            task, devices, before_start=self.parts.launches.before_uncaused, plan=plan
        )
        data = {"process_id": info.id, "devices": info.devices, "state": info.state}
        await self.updates.publish(
            "process_launched", f"process {info.id} launched with {', '.join(info.devices)}", data
        )
        return info

    async def devices(self) -> Sequence[DeviceView]:
        states = self.parts.states
        await states.wanted()
        running = self.manager.list()
        return [
            DeviceView(
                name=endpoint.name,
                driver=endpoint.driver,
                concurrency=endpoint.concurrency,
                backend=self.world.instances[endpoint.name].backend,
                status=endpoint.status,
                url=endpoint.url,
                state=states.get(endpoint.name),
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

    async def emergency_stop(self, reason: str) -> EmergencyStopReport:
        """Terminate every process, call every device's safe_stop, and latch until reset."""
        return await self.parts.estop.stop(reason)

    async def reset_emergency_stop(self) -> EmergencyStopState:
        """Unlatch the emergency stop (a person decided it is safe)."""
        return await self.parts.estop.reset()

    def emergency_stop_state(self) -> EmergencyStopState:
        return self.parts.estop.state()

    # --- devices -----------------------------------------------------------------------------------

    async def devices_settled(self) -> None:
        """Wait until every device, the background-start ones too, has had its first start attempt.

        ``start`` returns without waiting for those (the Reachy simulator boots for seconds).
        """
        await self.parts.hosting.settle(self.world.instances)

    def endpoints(self) -> dict[str, DeviceEndpoint]:
        """The world's devices as the process manager grants them (callers must not mutate it)."""
        return self.parts.endpoints()

    # --- lifecycle ---------------------------------------------------------------------------------

    async def start(
        self, host: str | None = None, port: int | None = None, *, wait_for_devices: bool = True
    ) -> str:
        """Start devices, the event store, the pool, the loop and the API; return the API's base URL.

        With ``wait_for_devices=False`` (``rosaos up``) it returns once the kernel can take
        commands, while the devices still come up: a launch that names a device still starting
        waits briefly for it (:class:`~rosaos.processes.manager.ProcessManager`)."""
        host = host or self.config.kernel.host
        port = self.config.kernel.port if port is None else port
        spans_off()  # the kernel's in-process tool calls: no spans to build (rosaos/fastmcp_spans.py)
        self._token = load_or_create_token(self.data_dir)  # creates the data directory, owner-only
        sock = await _bind_or_explain(host, port, self._token)
        self.url = _base_url(sock)
        try:
            self._parts = await build_parts(
                self._shutdown,
                config=self.config,
                world=self.world,
                models=self._models,
                process_model=self._process_model,
                worker_env=self._worker_env,
                hosting=self._hosting,
                token=self._token,
                url=self.url,
                wait_for_devices=wait_for_devices,
            )
            await self._serve(sock)
        except BaseException:
            await self.stop()
            sock.close()
            raise
        for name, work in self._parts.background().items():
            self._tasks.append(asyncio.create_task(work, name=name))
        self._started = True
        write_atomic(kernel_file(self.data_dir), json.dumps({"url": self.url, "pid": os.getpid()}))
        return self.url

    async def _serve(self, sock: socket.socket) -> None:
        """Start the HTTP API on ``sock``; return once it accepts connections."""
        allowed = [*self.config.kernel.allow_hosts, *bound_hosts(sock.getsockname()[0])]
        app = create_app(self, allowed_hosts=allowed, images_dir=self.data_dir / "images")
        config = uvicorn.Config(app, log_level="warning", lifespan="on", timeout_graceful_shutdown=3)
        self._server = uvicorn.Server(config)
        serving = asyncio.create_task(self._server.serve(sockets=[sock]), name="kernel api")
        self._tasks.append(serving)
        while not self._server.started:
            if serving.done():
                serving.result()
                raise KernelError("the kernel API stopped during start-up")
            await asyncio.sleep(0.01)

    async def stop(self) -> None:
        """Shut everything down: no orphan processes; unhandled events stay queued for next time."""
        for task in reversed(self._tasks):
            if task.get_name() == "kernel api" and self._server is not None:
                self._server.should_exit = True
            else:
                task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        self._tasks.clear()
        await self._shutdown.aclose()  # the pool, then the devices, then the event store
        if self._started and running_kernel_url(self.data_dir) == self.url:
            kernel_file(self.data_dir).unlink(missing_ok=True)
        self._started = False

    def login_link(self) -> str:
        """A fresh one-time link that logs the web page in."""
        return login_url(self.url + "/", self.login_codes.mint())


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


def events_path(data_dir: Path) -> Path:
    """Where the kernel keeps its event store."""
    return data_dir / EVENTS_FILE
