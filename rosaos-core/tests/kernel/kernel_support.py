"""Helpers for the kernel tests: the token, a small in-test runtime, and a polling wait.

``TestRuntime`` implements :class:`rosaos.kernel.api.schemas.KernelRuntime` with a fixed list of processes
and devices; integration tests with the real process manager and device supervisor live elsewhere.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from typing import Any

from rosaos.confirmations.confirmation_desk import ConfirmationDesk
from rosaos.events.plan import Plan
from rosaos.kernel.activity import ActivityLog
from rosaos.kernel.api.login_codes import LoginCodes
from rosaos.kernel.api.schemas import DeviceView, EmergencyStopReport, EmergencyStopState, Understanding
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.intake import Intake
from rosaos.kernel.updates import UpdateStream
from rosaos.memory.sightings import SightingLog
from rosaos.memory.store import MemoryStore
from rosaos.timers.timer_book import TimerBook

TOKEN = "test-token-0123456789"
ORIGIN = "http://127.0.0.1:8765"
AUTH = {"Authorization": f"Bearer {TOKEN}"}


@dataclass
class Process:
    """Stands in for ``rosaos.processes.manager.ProcessInfo`` (the API reads attributes)."""

    id: int
    task: str
    devices: list[str]
    state: str = "running"
    started_at: datetime = field(default_factory=lambda: datetime.now(UTC))
    ended_at: datetime | None = None
    worker_pid: int | None = 4242
    plan: Plan | None = None
    then: str | None = None


@dataclass
class TestRuntime:
    """A :class:`KernelRuntime` with canned processes and devices, recording what the API asks."""

    __test__ = False  # not a test class, despite the name

    events: EventStore
    updates: UpdateStream
    token: str = TOKEN
    login_codes: LoginCodes = field(default_factory=LoginCodes)
    model_description: str = "offline default"
    model_notice: str | None = "No model is configured: set [models] kernel in rosaos.toml."
    process_list: list[Process] = field(default_factory=list)
    device_list: list[dict[str, Any]] = field(default_factory=list)
    terminated: list[int] = field(default_factory=list)
    estop_reason: str | None = None
    estop_time: datetime | None = None
    untold_hosts: list[str] = field(default_factory=list)
    activity: ActivityLog | None = None
    """Set by fixtures that need ``GET /activity`` (it shares the event store's database)."""
    confirmations: ConfirmationDesk = field(default_factory=lambda: ConfirmationDesk(timeout=60))
    timers: TimerBook | None = None
    """Set by the ``runtime`` fixture (opening the table needs the event loop)."""
    memory: MemoryStore | None = None
    sightings: SightingLog | None = None
    """Both set by the ``runtime`` fixture, on a memory.db of the test's own."""
    intake: Intake = field(init=False)
    """The kernel's own intake on this store: the routes queue through it as in ``rosaos up``."""

    def __post_init__(self) -> None:
        self.intake = Intake(self.events, self.updates)

    async def processes(self, include_ended: bool = False) -> Sequence[Any]:
        return [p for p in self.process_list if include_ended or p.state == "running"]

    async def terminate(self, process_id: int) -> Any:
        for process in self.process_list:
            if process.id == process_id:
                self.terminated.append(process_id)
                process.state, process.ended_at = "terminated", datetime.now(UTC)
                return process
        raise KeyError(f"no process {process_id}")

    async def launch(self, task: str, devices: list[str], plan: Plan | None = None) -> Any:
        """Records the process as running; the real kernel hands it to a worker."""
        process = Process(
            id=max((p.id for p in self.process_list), default=0) + 1, task=task, devices=devices, plan=plan
        )
        self.process_list.append(process)
        return process

    async def devices(self) -> Sequence[DeviceView]:
        return [DeviceView.model_validate(device) for device in self.device_list]

    async def emergency_stop(self, reason: str) -> EmergencyStopReport:
        self.estop_reason, self.estop_time = reason, datetime.now(UTC)
        return EmergencyStopReport(latched=True, reason=reason, time=self.estop_time)

    async def reset_emergency_stop(self) -> EmergencyStopState:
        self.estop_reason = self.estop_time = None
        return self.emergency_stop_state()

    def emergency_stop_state(self) -> EmergencyStopState:
        return EmergencyStopState(
            latched=self.estop_reason is not None,
            reason=self.estop_reason,
            time=self.estop_time,
            untold_hosts=self.untold_hosts,
        )

    async def understand(self, text: str) -> Understanding:
        return Understanding(text=text, complete=False, kind="no_engine")  # no engine here


def kitchen_light(on: bool = False) -> dict[str, Any]:
    return {
        "name": "kitchen_light",
        "driver": "tapo",
        "concurrency": "exclusive",
        "backend": "sim",
        "status": "healthy",
        "url": "http://127.0.0.1:9101/mcp",
        "state": {"on": on, "brightness": 100},
        "description": "Ceiling light in the kitchen",
    }


async def eventually(
    condition: Callable[[], bool | Awaitable[bool]], within: float = 10.0, message: str = "condition"
) -> None:
    """Poll ``condition`` until it holds, failing after ``within`` seconds (never a timing assertion)."""
    try:
        async with asyncio.timeout(within):
            while True:
                result = condition()
                if not isinstance(result, bool):
                    result = await result
                if result:
                    return
                await asyncio.sleep(0.02)
    except TimeoutError:
        raise AssertionError(f"{message} did not happen within {within} s") from None
