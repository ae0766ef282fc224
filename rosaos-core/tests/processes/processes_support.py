"""Helpers shared by the process tests: the test device, the kernel stand-in, job building, polling.

``conftest.py`` puts this folder on ``sys.path`` so test modules can import this module, and so the
in-process worker tests can import ``process_test_models`` like the worker subprocesses do.
"""

from __future__ import annotations

import asyncio
import itertools
import os
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from pydantic import Field

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.drivers import Concurrency
from rosaos.events.callback import WorkerCallback
from rosaos.models.select import ModelSpec
from rosaos.processes.jobs import GrantedDevice, WorkerJob

TOKEN = "device-token"
KERNEL_TOKEN = "kernel-token"
_process_ids = itertools.count(1)


IMPORT_ROOT = Path(__file__).parents[__package__.count(".") + 1]
"""Where this folder's package name starts: pytest imports test folders as packages named from
the rootdir (``rosaos-core.tests.processes``), and worker subprocesses import them from here."""


def module_name(name: str) -> str:
    """The importable name of this folder's module ``name``, the same in the tests and in workers."""
    return f"{__package__}.{name}"


def model_spec(name: str) -> ModelSpec:
    """A model from ``process_test_models``: in-process jobs find the module the tests imported,
    worker subprocesses import it by the same name (:data:`IMPORT_ROOT` is on their PYTHONPATH)."""
    return ModelSpec(model=f"python:{module_name('process_test_models')}:{name}")


PYCACHE = Path(tempfile.gettempdir()) / "rosaos-test-worker-pycache"


def worker_env() -> dict[str, str]:
    """Environment for worker subprocesses: :data:`IMPORT_ROOT` on PYTHONPATH, so they find the test models.

    These tests start a dozen workers. Where bytecode writing is turned off
    (PYTHONDONTWRITEBYTECODE), each would compile pydantic-ai from source again, so their bytecode
    goes to a cache of their own instead; an ordinary install has it precompiled anyway.
    """
    paths = [str(IMPORT_ROOT), os.environ.get("PYTHONPATH", "")]
    env = {"PYTHONPATH": os.pathsep.join(path for path in paths if path)}
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        env |= {"PYTHONDONTWRITEBYTECODE": "", "PYTHONPYCACHEPREFIX": str(PYCACHE)}
    return env


def new_process_id() -> int:
    """Process ids unique across the test session, as the kernel's would be."""
    return next(_process_ids)


async def eventually(check: Callable[[], Any], within: float = 30.0, what: str = "condition") -> Any:
    """Poll ``check`` until it returns something truthy; fail with ``what`` after ``within`` s."""
    deadline = asyncio.get_running_loop().time() + within
    while True:
        result = check()
        if result:
            return result
        if asyncio.get_running_loop().time() > deadline:
            raise AssertionError(f"timed out after {within:g} s waiting for {what}")
        await asyncio.sleep(0.05)


def pid_alive(pid: int) -> bool:
    """Whether a process with ``pid`` exists (a reaped pid does not)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


@dataclass
class LoopbackDevice:
    """A test device served over HTTP; ``state`` is the live state its tools change."""

    name: str
    url: str
    state: dict[str, Any]

    def granted(self) -> GrantedDevice:
        return GrantedDevice(
            name=self.name,
            driver="testdevice",
            url=self.url,
            token=TOKEN,
            description=f"A dimmable test device called {self.name}.",
            prompt="Use set_level to change the level (0-100) and get_state to read it.",
        )

    def endpoint(
        self, concurrency: Concurrency = "exclusive", always_attached: bool = False
    ) -> DeviceEndpoint:
        granted = self.granted()
        return DeviceEndpoint(
            name=self.name,
            driver=granted.driver,
            concurrency=concurrency,
            always_attached=always_attached,
            description=granted.description,
            prompt=granted.prompt,
            url=self.url,
            token=TOKEN,
            status="healthy",
        )


def build_test_device(name: str, state: dict[str, Any]) -> FastMCP:
    server = FastMCP(name)

    @server.tool(annotations={"readOnlyHint": False, "destructiveHint": False, "idempotentHint": True})
    def set_level(level: Annotated[int, Field(ge=0, le=100, description="Level in percent.")]) -> str:
        """Set the device level, 0-100."""
        if state.get("jammed"):
            raise ToolError(f"{name} is jammed; free it and try again")
        state["level"] = level
        return f"{name} level is {level}"

    @server.tool(annotations={"readOnlyHint": True})
    def get_state() -> dict[str, Any]:
        """The device state as JSON."""
        return dict(state)

    return server


@dataclass
class KernelStandIn:
    """The kernel API a worker knows (``kernel_url``); records any body posted to ``POST /event``.

    A worker must post nothing there: a process's end goes to the pool over the worker's pipe.
    """

    url: str
    bodies: list[dict[str, Any]] = field(default_factory=list)


def make_job(
    kernel: KernelStandIn,
    model: str,
    devices: list[LoopbackDevice] | None = None,
    *,
    timeout: float = 30.0,
    request_limit: int = 10,
    process_id: int | None = None,
) -> WorkerJob:
    """A job for one test model; the worker knows the kernel stand-in's URL."""
    return WorkerJob(
        process_id=process_id or new_process_id(),
        task=f"run the {model} test",
        devices=[device.granted() for device in devices or []],
        model=model_spec(model),
        base_prompt="You are a test process.",
        timeout=timeout,
        request_limit=request_limit,
        kernel_url=kernel.url,
        kernel_token=KERNEL_TOKEN,
    )


@dataclass
class Endings:
    """What the pool reported through ``on_ended``, per process id."""

    reports: dict[int, list[WorkerCallback]] = field(default_factory=dict)

    async def record(self, callback: WorkerCallback) -> None:
        self.reports.setdefault(callback.process_id, []).append(callback)

    async def wait(self, process_id: int) -> WorkerCallback:
        """The one report for ``process_id``, once it arrives."""
        reports = await eventually(lambda: self.reports.get(process_id), what=f"process {process_id} to end")
        assert len(reports) == 1, reports
        return reports[0]


def parent_pid(pid: int) -> int:
    """The parent of a running process, from /proc."""
    stat = Path(f"/proc/{pid}/stat").read_text()
    return int(stat.rsplit(")", 1)[1].split()[1])


def process_running(pid: int) -> bool:
    """Whether ``pid`` exists and has not exited (a zombie, exited but not yet reaped, has)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return False
    return state not in ("Z", "X")


def wait_until_dead(pid: int, within: float = 10.0) -> None:
    """Block until ``pid`` has exited, without letting the event loop run (so the pool cannot notice)."""
    deadline = time.monotonic() + within
    while process_running(pid):
        if time.monotonic() > deadline:
            raise AssertionError(f"process {pid} did not exit within {within:g} s")
        time.sleep(0.01)


def wait_until_parked(name: str, within: float = 30.0) -> None:
    """Wait until a fork server has bound the park ``name`` (an abstract UNIX socket).

    A server parks only after it sees its kernel's socket close: a pool started before that finds
    no one parked and starts a fresh server (CI once lost an adoption test to that race)."""
    deadline = time.monotonic() + within
    while f"@{name}" not in Path("/proc/net/unix").read_text():
        assert time.monotonic() < deadline, f"no fork server parked as {name!r} within {within:g} s"
        time.sleep(0.05)
