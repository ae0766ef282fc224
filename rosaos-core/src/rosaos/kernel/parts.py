"""The kernel's composition root: every part built once, in start-up order, then frozen.

:func:`build_parts` is the one place that knows how the kernel is wired. Each part that must be
shut down registers that on the caller's :class:`contextlib.AsyncExitStack` as soon as it exists,
so a start that fails halfway stops exactly what it started, and :meth:`Kernel.stop` unwinds the
same stack: no part is ever looked up with ``hasattr``. The order matters and is the order below:

1. the event store, and what shares its SQLite file (updates, activity, timers), and the intake;
2. devices and the worker pool, side by side (both take seconds);
3. the devices a dead kernel's processes held are settled, then :func:`recover_orphans` makes
   them safe and queues those processes' ends, before anything can be granted;
4. the kernel agent's tools and the kernel loop.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Coroutine, Mapping
from dataclasses import dataclass
from typing import Any

from rosaos.config import RosaosConfig
from rosaos.confirmations.confirmation_chat import answer_from_chat, ask_people, record_confirmation
from rosaos.confirmations.confirmation_desk import ConfirmationDesk
from rosaos.devices.hosting import DeviceHosting
from rosaos.devices.state_cache import DeviceStateCache
from rosaos.devices.supervisor import DeviceSupervisor
from rosaos.devices.world import World
from rosaos.events.plan import Plan
from rosaos.kernel.activity import ActivityLog
from rosaos.kernel.agent import KernelPrompt, build_kernel_agent
from rosaos.kernel.device_directory import DeviceDirectory
from rosaos.kernel.device_status import DeviceStatusUpdates
from rosaos.kernel.emergency_stop import EmergencyStopControl, stored_emergency_stop
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.host_latch import HostLatches, keep_latch
from rosaos.kernel.intake import Intake, Queued
from rosaos.kernel.launch_cause import CurrentEvent, LaunchCause
from rosaos.kernel.loop import KernelLoop
from rosaos.kernel.orphans import LiveProcesses, recover_orphans
from rosaos.kernel.pending_stops import PendingStops, StopUndelivered
from rosaos.kernel.process_ends import ProcessEnds, end_event
from rosaos.kernel.stop_at_intake import StopAtIntake
from rosaos.kernel.stop_tools import add_stop_tools
from rosaos.kernel.stopping import Stopper
from rosaos.kernel.tools import build_kernel_tools
from rosaos.kernel.updates import UpdateStream
from rosaos.memory.memory_tools import add_memory_tools, memory_summary
from rosaos.memory.sightings import SightingLog
from rosaos.memory.store import MemoryStore
from rosaos.models.defaults import KernelModels
from rosaos.models.select import ModelSpec
from rosaos.notices.notice_watcher import NoticeWatcher
from rosaos.processes.fork_parking import park_name
from rosaos.processes.jobs import WorkerCallback
from rosaos.processes.manager import LaunchRefused, ProcessInfo, ProcessManager
from rosaos.processes.pool import WorkerPool
from rosaos.processes.prompts import base_process_prompt
from rosaos.timers.timer_book import TimerBook
from rosaos.timers.timer_tools import add_timer_tools

log = logging.getLogger(__name__)

EVENTS_FILE = "kernel.sqlite3"


@dataclass(frozen=True)
class KernelParts:
    """Everything a running kernel is made of; built once by :func:`build_parts`."""

    store: EventStore
    updates: UpdateStream
    activity: ActivityLog
    intake: Intake
    timers: TimerBook
    confirmations: ConfirmationDesk
    hosting: DeviceHosting
    endpoints: DeviceDirectory
    manager: ProcessManager
    launches: LaunchRecords
    memory: MemoryStore
    sightings: SightingLog
    pending_stops: PendingStops
    host_latches: HostLatches
    estop: EmergencyStopControl
    states: DeviceStateCache
    stopper: Stopper
    loop: KernelLoop
    notices: NoticeWatcher
    background_later: bool = False
    """The background-start devices are released once the others settled, by a task of
    :meth:`background` (``rosaos up``'s early banner), not before the API opened."""

    def background(self) -> dict[str, Coroutine[Any, Any, None]]:
        """The tasks that run for as long as the kernel does, by name (started after the API)."""
        tasks: dict[str, Coroutine[Any, Any, None]] = {
            "device states": self.states.run(),
            "device notices": self.notices.run(),
            "pending safe stops": self.pending_stops.run(),
            "host latches": self.host_latches.run(),
            "kernel loop": _run_loop(self.loop, self.updates),
            # Timers that fell due while the kernel was down fire now, once, and say they are late.
            "timers": self.timers.run(),
        }
        if self.background_later:  # still after the other devices, but without holding up the banner
            tasks["background devices"] = _release_background(self.hosting)
        return tasks


class LaunchRecords:
    """What happens before a worker has a job: ids kept unique across restarts, and the process
    and its cause remembered until its end is recorded. A crash after this leaves an orphan record."""

    def __init__(self, store: EventStore, live: LiveProcesses, pending_stops: PendingStops) -> None:
        self._store = store
        self._live = live
        self._pending_stops = pending_stops

    async def before(self, info: ProcessInfo, cause: LaunchCause | None) -> None:
        """A launch a kernel event step caused (``cause``), or one from outside the loop (None)."""
        try:
            await self._pending_stops.before_grant(info.devices)
        except StopUndelivered as owed:
            raise LaunchRefused(str(owed)) from None
        await self._live.launched(info, cause)  # notes its id too, in the same commit

    async def before_uncaused(self, info: ProcessInfo) -> None:
        """A launch no event step caused (a card control, a memory tool): recorded all the same."""
        await self.before(info, None)


async def build_parts(
    stack: contextlib.AsyncExitStack,
    *,
    config: RosaosConfig,
    world: World,
    models: KernelModels,
    process_model: ModelSpec,
    worker_env: Mapping[str, str] | None,
    hosting: DeviceHosting | None,
    token: str,
    url: str,
    wait_for_devices: bool = True,
) -> KernelParts:
    """Build, start and wire every part of the kernel but its API; see the module docstring."""
    data_dir, kernel = config.data_dir, config.kernel
    store = await EventStore.open(data_dir / EVENTS_FILE)
    stack.push_async_callback(store.close)
    updates = await UpdateStream.open(store.database)
    activity = await ActivityLog.open(store.database)
    intake = Intake(store, updates)
    live = LiveProcesses(store)
    timers = await TimerBook.open(store, intake.submit)
    # A device that boots in the background (the Reachy simulator: seconds of CPU) waits until
    # the other devices and the workers are up: on two cores it would otherwise delay them.
    devices = hosting or DeviceSupervisor(world, data_dir, token, defer_background=True)
    stack.push_async_callback(devices.stop)
    endpoints = DeviceDirectory(devices, world, config, token)
    devices.on_status_change = DeviceStatusUpdates(updates, devices.host_of).changed
    confirmations = ConfirmationDesk(
        kernel.confirm_timeout,
        lambda item: ask_people(updates, endpoints(), item),
        record=lambda item: record_confirmation(activity, updates, item),
    )

    async def process_ended(callback: WorkerCallback) -> None:
        await intake.submit(end_event(callback))

    pool = WorkerPool(
        size=kernel.pool_size,
        env=worker_env,
        fork_server=kernel.fork_server,
        max_workers=kernel.max_workers,
        park=park_name(data_dir),  # a kernel restarted after a crash adopts its fork server, warm
    )
    manager = ProcessManager(
        devices=endpoints,
        model=process_model,
        base_prompt=base_process_prompt(kernel.process_prompt),
        job_timeout=kernel.job_timeout,
        request_limit=kernel.request_limit,
        kernel_url=url,
        kernel_token=token,
        pool=pool,
        on_ended=process_ended,
        first_process_id=await store.next_process_id(),
        emergency_stop=await stored_emergency_stop(store),
        starting=devices.settle,
    )
    stack.push_async_callback(manager.stop)
    keep_latch(data_dir, manager.emergency_stop)  # a host starts latched from its first moment
    # Devices (a robot simulator takes seconds to boot) and the warm workers (seconds of
    # imports each) start side by side; neither needs the other until the first event.
    # With ``wait_for_devices=False`` (``rosaos up``) neither is waited for: a launch waits for a
    # device still starting (``starting`` above) and for the pool (``manager.warming``).
    try:
        async with asyncio.TaskGroup() as group:
            group.create_task(devices.start(wait=wait_for_devices), name="start devices")
            if wait_for_devices:
                group.create_task(manager.start(), name="start worker pool")
            else:
                manager.start_in_background()
    except BaseExceptionGroup as failed:
        raise failed.exceptions[0] from None
    pending_stops = PendingStops(
        store, devices.directory, lambda text, data: updates.publish("notice", text, data)
    )
    # Before the loop can grant anything: devices a dead kernel's processes held, or owed a
    # safe_stop by the last run, get it, so one still starting (the Reachy simulator) is waited for.
    if wait_for_devices:
        devices.release_background()
    owed = {name for p in await live.left() for name in p.devices}
    owed |= set(await pending_stops.names())
    if manager.emergency_stop is not None and not wait_for_devices:
        await devices.foreground_settled()  # each host hears of the latch before "up"
    await devices.settle(owed)
    # Opened before orphan recovery: a process end it queues records its sightings.
    memory = MemoryStore.open(data_dir)
    origins = {
        n: (d.map_origin.x, d.map_origin.y, d.map_origin.yaw)
        for n, d in config.devices.items()
        if d.map_origin
    }
    sightings = SightingLog(memory, config.memory.sightings_days, origins, data_dir / "images")
    # Side effects of an event's arrival: registered here, before anything can queue an event
    # (orphan recovery below is the first). The intake runs them once the event is committed and
    # published, whether or not a kernel turn is running (kernel/intake.py). A per-event action
    # that must not wait for the kernel agent, such as obeying a spoken or typed "stop" at once,
    # is registered the same way, for "user_said" and "user_typed" (anywhere in this function:
    # the API, the notices and the timers start queueing only after it returns).
    intake.on("worker_callback", ProcessEnds(manager, activity, sightings, updates, live).arrived)
    await pending_stops.deliver()  # owed by the last run: a device that is back is stopped now
    host_latches = HostLatches(devices.directory, data_dir)
    if manager.emergency_stop is not None:  # latched before the restart: so are the hosts
        await host_latches.push(True, manager.emergency_stop.reason)
    stops = await recover_orphans(live, devices.directory(), intake.submit, remember=manager.remember)
    await pending_stops.note(stops)
    launches = LaunchRecords(store, live, pending_stops)
    current = CurrentEvent()
    tools = build_kernel_tools(
        manager, endpoints, current=current, before_start=launches.before, launched_before=live.launched_for
    )
    add_timer_tools(tools, timers)

    async def launch(task: str, names: list[str], plan: Plan) -> ProcessInfo:
        """Launch a process as ``launch_process`` does (a memory tool's: drive to a place)."""
        return await manager.launch(task, names, before_start=launches.before_uncaused, plan=plan)

    add_memory_tools(tools, memory, endpoints, launch, sightings)
    if models.local is not None:
        models.local.memory = memory
    stopper = Stopper(manager, endpoints, lambda name: world.instances[name].spec.halts)
    stop_at_intake = StopAtIntake.for_world(
        stopper, world, config.models.language, updates.publish, aliases=memory.aliases
    )

    async def stop_now(queued: Queued) -> None:
        """A typed or spoken "stop" acts at once, beside whatever turn the kernel is in."""
        stop_at_intake.heard(queued.id, queued.event)

    intake.on("user_typed", stop_now)
    intake.on("user_said", stop_now)
    add_stop_tools(
        tools, stopper, manager, endpoints, lambda report: stop_at_intake.merged(current.event_id, report)
    )
    prompt = KernelPrompt(kernel.kernel_prompt)
    loop = KernelLoop(
        store,
        updates,
        build_kernel_agent(models.kernel, tools),
        instructions=lambda: prompt(endpoints()) + memory_summary(memory),
        model=models.for_event,
        history_budget=kernel.history_messages,
        current=current,
        history_chars=kernel.history_chars,
        relay_reports=kernel.relay_reports,
    )
    loop.before = lambda event: answer_from_chat(confirmations, event)
    return KernelParts(
        store=store,
        updates=updates,
        activity=activity,
        intake=intake,
        timers=timers,
        confirmations=confirmations,
        hosting=devices,
        endpoints=endpoints,
        manager=manager,
        launches=launches,
        memory=memory,
        sightings=sightings,
        pending_stops=pending_stops,
        host_latches=host_latches,
        estop=EmergencyStopControl(
            manager, devices.safe_stop_all, store, updates, host_latches, pending_stops
        ),
        states=DeviceStateCache(endpoints),
        stopper=stopper,
        loop=loop,
        notices=NoticeWatcher(endpoints, intake.submit),
        background_later=not wait_for_devices,
    )


async def _release_background(devices: DeviceHosting) -> None:
    await devices.foreground_settled()
    devices.release_background()


async def _run_loop(loop: KernelLoop, updates: UpdateStream) -> None:
    try:
        await loop.run_forever()
    except asyncio.CancelledError:
        raise
    except Exception:  # the loop must not die silently: say so where the user looks
        log.exception("the kernel loop stopped")
        await updates.publish("error", "the kernel loop stopped; see the console log")
        raise
