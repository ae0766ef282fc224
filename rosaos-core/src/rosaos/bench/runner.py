"""Run task files through the full system: one kernel per file, every task from a clean start.

For each file: resolve its world on sim backends (:mod:`rosaos.bench.sim_world`), start one
:class:`~rosaos.kernel.runtime.Kernel` on it (event store, worker pool, kernel agent, HTTP API),
and for each task and trial:

1. wait until the previous task has left nothing behind (queue empty, no process running);
2. forget the kernel's conversation (and any latched emergency stop), restart every simulator
   from the file's ``state`` plus the task's ``setup``, and check that they report that state;
3. ``POST /stt`` the sentence, exactly as the voice front end does, and wait until the queue is
   empty and no process runs (60 s at most);
4. read every device through ``get_state`` over MCP HTTP and apply :mod:`rosaos.bench.expect`.

Nothing here looks at a task's id or sentence: held-out task files run the same way.
"""

from __future__ import annotations

import asyncio
import fnmatch
import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from pydantic_ai.messages import ModelMessage, ModelResponse
from pydantic_ai.models import Model, ModelRequestParameters
from pydantic_ai.models.wrapper import WrapperModel
from pydantic_ai.settings import ModelSettings

from rosaos.bench.expect import device_differences, reply_matches, world_differences
from rosaos.bench.results import DifferenceView, FileResult, Summary, TaskResult, TrialResult
from rosaos.bench.sim_world import BenchWorld, SimDevices, bench_world
from rosaos.bench.tasks import BenchTask, TaskFile, TaskSelection
from rosaos.config import RosaosConfig
from rosaos.kernel.api.kernel_client import KernelClient
from rosaos.kernel.runtime import Kernel
from rosaos.kernel.updates import Update
from rosaos.plugins import DriverRegistry

IDLE_TIMEOUT = 30.0
"""How long a task waits for leftovers of the previous one (e.g. after a timeout) to finish."""
POLL_INTERVAL = 0.01
CONFIRM_DELAY = 0.05
"""Settling is confirmed by a second look: a crashed process ends a moment before the kernel
enqueues its callback, and that moment must not pass for "settled"."""
MAX_REASON_DIFFERENCES = 3
WORKER_LOG_ENV = "ROSAOS_WORKER_LOG"


def select_tasks(files: Sequence[TaskFile], patterns: Sequence[str]) -> list[TaskSelection]:
    """The tasks whose id matches one of the glob ``patterns`` (all when none); files with none are left out."""
    selections = []
    for task_file in files:
        tasks = [
            task
            for task in task_file.tasks
            if not patterns or any(fnmatch.fnmatchcase(task.id, pattern) for pattern in patterns)
        ]
        if tasks:
            selections.append(TaskSelection(task_file, tasks))
    return selections


class BenchProgress(Protocol):
    """What the runner reports while it goes (the progress bar)."""

    def started(self, task_id: str, trial: int) -> None: ...

    def finished(self, task_id: str, result: TrialResult | None) -> None:
        """A trial ended (None: the task is pending and was not run)."""


class _CountingModel(WrapperModel):
    """Counts the kernel's model requests; answers exactly as the wrapped model does."""

    def __init__(self, wrapped: Model, counter: RequestCounter) -> None:
        super().__init__(wrapped)
        self._counter = counter

    async def request(
        self,
        messages: list[ModelMessage],
        model_settings: ModelSettings | None,
        model_request_parameters: ModelRequestParameters,
    ) -> ModelResponse:
        self._counter.requests += 1
        return await self.wrapped.request(messages, model_settings, model_request_parameters)


@dataclass
class RequestCounter:
    """Kernel model requests since the last :meth:`reset`. Workers report their own in callbacks."""

    requests: int = 0
    _wrappers: dict[int, Model] = field(default_factory=dict)

    def install(self, kernel: Kernel) -> None:
        """Wrap every model the kernel loop picks (routing stays as it was: only counted)."""
        loop = kernel.loop
        default = loop.agent.model
        choose = loop.model_for

        def counted(event: Any) -> Model | None:
            model = choose(event) or default
            if not isinstance(model, Model):
                return None
            if id(model) not in self._wrappers:
                self._wrappers[id(model)] = _CountingModel(model, self)
            return self._wrappers[id(model)]

        loop.model_for = counted

    def reset(self) -> None:
        self.requests = 0


@dataclass
class _Activity:
    """What the updates of one trial say the system did."""

    model_calls: int = 0
    tool_calls: int = 0
    processes: int = 0
    replies: list[str] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)

    @classmethod
    def of(cls, updates: Sequence[Update], kernel_requests: int) -> _Activity:
        activity = cls(model_calls=kernel_requests)
        ended: set[int] = set()
        for update in updates:
            if update.kind == "tool_call":
                activity.tool_calls += 1
            elif update.kind == "process_launched":
                activity.processes += 1
            elif update.kind == "kernel_reply":
                activity.replies.append(update.text)
            elif update.kind == "error":
                activity.errors.append(update.text)
            elif update.kind == "process_ended" and update.data.get("process_id") not in ended:
                ended.add(update.data.get("process_id", 0))
                activity.model_calls += int(update.data.get("model_requests", 0))
                activity.tool_calls += int(update.data.get("tool_calls", 0))
        return activity


async def run_file(
    selection: TaskSelection,
    config: RosaosConfig,
    registry: DriverRegistry,
    repeat: int,
    progress: BenchProgress,
) -> FileResult:
    """Run the selected tasks of one file, each ``repeat`` times, on one kernel."""
    task_file = selection.file
    world = bench_world(task_file, registry)
    tasks: dict[str, TaskResult] = {t.id: TaskResult(id=t.id, say=t.said) for t in selection.tasks}
    runnable: list[BenchTask] = []
    for task in selection.tasks:
        named = [*task.expect, *task.setup]
        pending = [f"{d}: {world.unavailable[d]}" for d in dict.fromkeys(named) if d in world.unavailable]
        invalid = [f"{d}: {world.invalid[d]}" for d in dict.fromkeys(named) if d in world.invalid]
        if pending and not invalid:
            tasks[task.id].pending = "; ".join(pending)
            progress.finished(task.id, None)
        else:
            runnable.append(task)
    error = None
    if runnable:
        error = await _run_on_kernel(task_file, world, runnable, tasks, config, repeat, progress)
    results = list(tasks.values())
    return FileResult(
        path=str(task_file.path), name=task_file.name, tasks=results, summary=Summary.of(results), error=error
    )


async def _run_on_kernel(
    task_file: TaskFile,
    world: BenchWorld,
    runnable: Sequence[BenchTask],
    tasks: Mapping[str, TaskResult],
    config: RosaosConfig,
    repeat: int,
    progress: BenchProgress,
) -> str | None:
    """Start the file's kernel, run every trial, stop it. Returns why the kernel could not start, if so."""
    hosting = SimDevices(world.world, config.data_dir)
    # Workers log each process at INFO on the terminal's stderr; the table says it better.
    quiet = {WORKER_LOG_ENV: os.environ.get(WORKER_LOG_ENV, "WARNING")}
    try:
        kernel = Kernel(config, world.world, devices=hosting, worker_env=quiet)
        await kernel.start(host="127.0.0.1", port=0)  # stops what it started when it fails
    except Exception as error:  # the file's world cannot come up: its tasks fail with the reason
        reason = f"the kernel did not start: {type(error).__name__}: {error}"
        for task in runnable:
            for _ in range(repeat):
                tasks[task.id].trials.append(TrialResult(status="error", reason=reason))
                progress.finished(task.id, tasks[task.id].trials[-1])
        return reason
    counter = RequestCounter()
    counter.install(kernel)
    try:
        async with KernelClient(kernel.url, kernel.token, timeout=30) as client:
            for task in runnable:
                for trial in range(1, repeat + 1):
                    progress.started(task.id, trial)
                    result = await _run_trial(kernel, hosting, world, task_file, task, counter, client)
                    tasks[task.id].trials.append(result)
                    progress.finished(task.id, result)
    finally:
        await kernel.stop()
    return None


async def _run_trial(
    kernel: Kernel,
    hosting: SimDevices,
    world: BenchWorld,
    task_file: TaskFile,
    task: BenchTask,
    counter: RequestCounter,
    client: KernelClient,
) -> TrialResult:
    """One task, once: clean start, post, settle, check. Any exception is this trial's error."""
    unchecked = {**world.unavailable, **world.invalid}
    try:
        if await _settle(kernel, IDLE_TIMEOUT) is None:
            return TrialResult(status="error", reason="the kernel was still busy with the previous task")
        kernel.loop.reset_conversation()
        if kernel.emergency_stop_state().latched:  # an earlier task's emergency stop must not leak
            await kernel.reset_emergency_stop()
        initial = task_file.initial_state(task)
        await hosting.restart(
            {name: world.simulator_state(name, initial[name]) for name in world.world.instances}
        )
        unchecked |= hosting.failures()
        named = set(task.expect) | set(task.setup)
        if missing := {d: why for d, why in unchecked.items() if d in named}:
            reason = "; ".join(f"{d}: {why}" for d, why in missing.items())
            return TrialResult(status="error", reason=f"cannot run: {reason}", unchecked=unchecked)
        before, unreadable = await hosting.read_states()
        off = [
            str(d)
            for name, state in before.items()
            for d in device_differences({}, initial[name], state, name)
        ]
        if off or unreadable:
            problems = off + [f"{name}: {why}" for name, why in unreadable.items()]
            return TrialResult(
                status="error",
                reason="the simulators did not start as the task file says: " + "; ".join(problems),
                unchecked=unchecked,
            )
        last_update = await kernel.updates.last_id()
        counter.reset()
        posted = time.monotonic()
        await _say(client, task)
        settled_at = await _settle(kernel, max(task.settle - (time.monotonic() - posted), 0.0))
        if settled_at is None:
            await _terminate_all(kernel)
        after, unreadable = await hosting.read_states()
        activity = _Activity.of(await _updates_after(kernel, last_update), counter.requests)
    except Exception as error:  # this trial fails with its reason; the run goes on
        return TrialResult(status="error", reason=f"{type(error).__name__}: {error}", unchecked=unchecked)
    if unreadable:  # a device that answered before the task and not after: its check cannot be skipped
        lost = "; ".join(f"{name}: {why}" for name, why in unreadable.items())
        return TrialResult(status="error", reason=f"cannot read the state after the task: {lost}")
    replies = activity.replies + _spoken(initial, after)
    differences = world_differences(task.expect, initial, after)
    reply_ok = reply_matches(task.reply, replies) if task.reply is not None else None
    problems = [str(d) for d in differences[:MAX_REASON_DIFFERENCES]]
    if len(differences) > MAX_REASON_DIFFERENCES:
        problems.append(f"... {len(differences) - MAX_REASON_DIFFERENCES} more")
    if reply_ok is False:
        problems.append(f"no reply matches {task.reply!r}")
    status = "pass"
    if settled_at is None:
        status, problems = "error", [f"did not settle within {task.settle:g} s", *problems]
    elif problems:
        status = "fail"
    return TrialResult(
        status=status,
        reason="; ".join(problems) or None,
        differences=[DifferenceView.of(d) for d in differences],
        reply_ok=reply_ok,
        latency_s=round(settled_at - posted, 4) if settled_at is not None else None,
        model_calls=activity.model_calls,
        tool_calls=activity.tool_calls,
        processes=activity.processes,
        replies=replies,
        kernel_errors=activity.errors,
        unchecked=unchecked,
    )


async def _say(client: KernelClient, task: BenchTask) -> None:
    """Post each thing the task says as a ``[User said]`` event, waiting ``after`` seconds before it."""
    for item in task.utterances:
        if item.after:
            await asyncio.sleep(item.after)
        await client.request("POST", "/stt", json={"text": item.text, "source": "bench"})


def _spoken(initial: Mapping[str, Mapping[str, Any]], after: Mapping[str, Mapping[str, Any]]) -> list[str]:
    """What a speaking device (the Reachy Mini's ``last_spoken``) said during the task: replies too."""
    return [
        state["last_spoken"]
        for name, state in after.items()
        if isinstance(state.get("last_spoken"), str)
        and state["last_spoken"]
        and state["last_spoken"] != initial.get(name, {}).get("last_spoken")
    ]


async def _idle(kernel: Kernel) -> bool:
    return await kernel.events.pending_count() == 0 and not await kernel.processes()


async def _settle(kernel: Kernel, timeout: float) -> float | None:
    """Wait until the queue is empty and no process runs; the monotonic time it first was, or None."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if await _idle(kernel):
            seen = time.monotonic()
            await asyncio.sleep(CONFIRM_DELAY)
            if await _idle(kernel):
                return seen
        await asyncio.sleep(POLL_INTERVAL)
    return None


async def _terminate_all(kernel: Kernel) -> None:
    """End what a timed-out task left running, so the next task starts clean."""
    for process in await kernel.processes():
        await kernel.terminate(process.id)


async def _updates_after(kernel: Kernel, update_id: int) -> list[Update]:
    updates: list[Update] = []
    while batch := await kernel.updates.after(update_id, 500):
        updates += batch
        update_id = batch[-1].id
    return updates
