"""The bench tasks, run offline: match the sentence, run the plans on simulators, check state.

The tasks are the public ones (``../shared/bench/tasks``) and rosaOS's own variants of them
(``benchmarks/tasks``), which stand in for the held-out files.

Two tests per task: the plan's shape (fast, no device), then the plan run on the drivers'
simulators with the state checked the way ``rosaos bench`` does (through ``get_state``).

Generic, like ``rosaos bench``: nothing here knows a sentence. A task is covered when every
device its ``expect`` names has an implemented driver that ships intents (today: the Tapo bulbs
of home.yaml), or when it expects no change at all (ambiguous, unknown, questions). The rules:

- a task that changes state must match exactly, launch processes for exactly the devices it
  names, and leave them as ``expect`` says (and every other initial key as it was);
- a task that expects no change must not actuate: either it is not an exact match (the engine
  asks or refuses), or its plans only read state;
- a ``reply`` regex must match some reply (the kernel's, or a process output), by ``rosaos.bench``'s rule;
  a state question the kernel answers itself (no lease, no process) is answered here the same
  way, from the task's initial states.

A task that is a conversation (several sentences: "the kitchen is at x 3.5, y 0", then "go to the
kitchen") needs the kernel between its sentences (memory, processes), so it runs the way
``rosaos bench`` runs it: the conversations of a file on one real kernel over the simulators, every
simulator restarted from the task's state between tasks, and each must pass.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastmcp import Client
from pydantic_ai import Agent
from pydantic_ai.mcp import MCPToolset

from rosaos.bench.expect import device_differences, reply_matches
from rosaos.bench.results import TrialResult
from rosaos.bench.runner import run_file
from rosaos.bench.tasks import BenchTask, TaskFile, TaskSelection, load_task_file
from rosaos.config import DeviceConfig, RosaosConfig
from rosaos.devices.serve import open_device
from rosaos.devices.world import build_world
from rosaos.events.plan import Plan
from rosaos.intents.grammar.vocabulary import sources_from_config
from rosaos.intents.understanding.match_result import MatchResult
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.intents.understanding.questions import read_question
from rosaos.intents.understanding.small_talk import read_small_talk, small_talk_reply
from rosaos.intents.understanding.stop_words import DeviceRefs
from rosaos.models.kernel_actions import help_text, state_answer
from rosaos.models.process_model import LocalPlanModel
from rosaos.plugins import DriverRegistry, load_drivers
from rosaos.processes.jobs import GrantedDevice
from rosaos.processes.prompts import DEFAULT_PROCESS_PROMPT, process_system_prompt

from .intents_support import BENCH_TASKS, OWN_TASKS
from .shared_reachy import lent_daemon, starts_awake

READ_ONLY_TOOLS = {"get_state"}
# Task files that no implementation can pass as written; reported to the bench's owner.
TASK_FILE_ISSUES: dict[str, str] = {}
REGISTRY = load_drivers()


ROBOT_DRIVERS = {"ros", "reachy"}
"""Drivers whose simulators are physics run in real time (a drive, the Reachy daemon)."""


TASK_FILES = [
    load_task_file(path) for path in [*sorted(BENCH_TASKS.glob("*.yaml")), *sorted(OWN_TASKS.glob("*.yaml"))]
]


def _is_conversation(task: BenchTask) -> bool:
    return len(task.utterances) > 1


def _tasks(slow: tuple[pytest.MarkDecorator, ...] = ()) -> list[Any]:
    """Every task of one sentence as a test parameter (conversations are run by file, in
    :func:`test_bench_conversations_run_on_one_kernel_per_file`); ``slow`` marks the tasks that move
    a robot (its simulator runs in real time): seconds each."""
    params = []
    for task_file in TASK_FILES:
        for task in task_file.tasks:
            if _is_conversation(task):
                continue
            robots = {task_file.world[device].driver for device in task.expect} & ROBOT_DRIVERS
            params.append(pytest.param(task_file, task, id=task.id, marks=slow if robots else ()))
    return params


def _conversation_files() -> list[Any]:
    """Every task file that has conversations, as a test parameter (a kernel each: slow)."""
    return [
        pytest.param(task_file, id=task_file.path.stem, marks=pytest.mark.slow)
        for task_file in TASK_FILES
        if any(_is_conversation(task) for task in task_file.tasks)
    ]


def _covered(world: TaskFile, task: BenchTask, registry: DriverRegistry) -> str | None:
    """Why the offline engine cannot be held to ``task`` yet, or None when it can."""
    for device in task.expect:
        driver = world.world[device].driver
        info = registry.drivers.get(driver)
        if info is None or not info.spec.implemented or info.spec.intents is None:
            return f"{device}: driver {driver!r} is a placeholder or ships no intents yet"
    return None


def _devices(world: TaskFile, task: BenchTask) -> tuple[dict[str, DeviceConfig], dict[str, Any]]:
    """The task's devices as config tables, each starting in its state plus the task's setup."""
    initial = world.initial_state(task)
    devices = {
        name: DeviceConfig(
            driver=entry.driver, description=entry.description, sim={**entry.sim, **initial[name]}
        )
        for name, entry in world.world.items()
    }
    return devices, initial


async def _run(
    task_text: str, plan: Plan, device: str, config: DeviceConfig, data_dir: Path
) -> tuple[str, dict[str, Any]]:
    """Run one process the way the worker does (the plan a field of the job); return its output
    and the device's state after."""
    # Only this device is built: other drivers of the world may be placeholders.
    instance = build_world(RosaosConfig(devices={device: config}), REGISTRY).get(device)
    granted = GrantedDevice(
        name=device,
        driver=instance.spec.name,
        url="-",
        token="-",
        description=instance.description,
        prompt="-",
    )
    async with open_device(instance, data_dir) as opened:
        agent = Agent(
            LocalPlanModel(plan=plan),
            system_prompt=process_system_prompt(DEFAULT_PROCESS_PROMPT, task_text, [granted]),
            toolsets=[MCPToolset(opened.server)],
        )
        output = (await agent.run(task_text)).output
        async with Client(opened.server) as client:  # state through get_state, as rosaos bench reads it
            state = (await client.call_tool("get_state", {})).structured_content or {}
    return output, state


_MATCHERS: dict[tuple[Any, ...], IntentMatcher] = {}


def _matcher(devices: dict[str, DeviceConfig]) -> IntentMatcher:
    """The matcher of a world, built once per vocabulary (building compiles grammars: seconds).

    A matcher reads names, descriptions, aliases, areas and the drivers' intents, never the sim
    state a task sets up, and it keeps no state between sentences (only a memo of its readings),
    so tasks of one world share it as the kernel shares one across commands.
    """
    sources = sources_from_config(devices, REGISTRY)
    key = tuple((s.name, s.driver, s.description, s.aliases, s.area) for s in sources)
    if key not in _MATCHERS:
        _MATCHERS[key] = IntentMatcher(sources)
    return _MATCHERS[key]


def _match(world: TaskFile, task: BenchTask) -> Any:
    """Skip an uncovered task; otherwise match its sentence in its world and check the plan's shape."""
    if (reason := _covered(world, task, REGISTRY)) is not None:
        pytest.skip(reason)
    devices, initial = _devices(world, task)
    if not task.expect and _kernel_answers(devices, initial, task):
        # The kernel answers a state question itself and never hands it to the matcher.
        return MatchResult("no_match", task.said), devices, initial
    result = _matcher(devices).match(task.said)
    planned = {step.tool for process in result.processes for step in process.plan.steps}
    if not task.expect and result.is_exact:
        assert planned <= READ_ONLY_TOOLS, f"{task.said!r} must change nothing, but plans {sorted(planned)}"
    if task.expect:
        assert result.is_exact, f"{task.said!r} did not match: {result.reply}"
        assert {device for process in result.processes for device in process.devices} == set(task.expect)
    return result, devices, initial


def _kernel_answers(devices: dict[str, DeviceConfig], initial: dict[str, Any], task: BenchTask) -> list[str]:
    """What the kernel answers a state question itself, before any match (no lease, no process):
    from the task's initial states, by the kernel's own words (``state_answer``). Empty when the
    states a task file sets do not say (a battery the simulator reports): the question's
    ``get_state`` plan is then run on the simulator instead."""
    vocabulary = sources_from_config(devices, REGISTRY)
    refs = DeviceRefs(vocabulary)
    question = read_question(task.said, refs)
    if task.expect:
        return []
    if question is None:  # small talk, answered in one line (``kernel_action_turn``'s rule)
        chat = read_small_talk(task.said, lambda word: refs.resolve(word) is not None)
        return [small_talk_reply(chat)] if chat is not None else []
    if question.topic == "help":
        return [help_text(vocabulary)]
    asked = question.devices or tuple(initial)
    return [
        answer for device in asked if (answer := state_answer(question, device, initial[device])) is not None
    ]


class _Quiet:
    def started(self, task_id: str, trial: int) -> None:
        pass

    def finished(self, task_id: str, result: TrialResult | None) -> None:
        pass


async def _converse(world: TaskFile, tasks: list[BenchTask], tmp_path: Path) -> dict[str, str]:
    """Run conversation tasks of one file on one kernel, as ``rosaos bench`` runs a file (each
    from a clean start: conversation forgotten, every simulator restarted from the task's state);
    why each one that did not pass failed, by task id."""
    config = RosaosConfig(data_dir=tmp_path / "data")
    result = await run_file(TaskSelection(world, tasks), config, REGISTRY, 1, _Quiet())
    assert [task.id for task in result.tasks] == [task.id for task in tasks]
    failures = {}
    for task, outcome in zip(tasks, result.tasks, strict=True):
        if outcome.pending is not None:
            failures[task.id] = f"{task.said!r}: pending: {outcome.pending}"
        elif [trial.status for trial in outcome.trials] != ["pass"]:
            failures[task.id] = (
                "; ".join(
                    f"{task.said!r}: {trial.status}: {trial.reason}; replies: {trial.replies}"
                    for trial in outcome.trials
                )
                or f"{task.said!r}: no trial ran"
            )
    return failures


@pytest.fixture(scope="module")
def shared_reachy(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    """One simulated Reachy daemon for the module's Reachy tasks (:mod:`.shared_reachy` says why)."""
    with lent_daemon(tmp_path_factory.mktemp("reachy-daemon")):
        yield


@pytest.mark.parametrize(("world", "task"), _tasks())
def test_bench_sentence_plans_the_expected_devices(world: TaskFile, task: BenchTask) -> None:
    _match(world, task)


@pytest.mark.parametrize(("world", "task"), _tasks(slow=(pytest.mark.slow,)))
async def test_bench_task_runs_on_simulators(
    world: TaskFile, task: BenchTask, tmp_path: Path, request: pytest.FixtureRequest
) -> None:
    if task.id in TASK_FILE_ISSUES:
        pytest.xfail(TASK_FILE_ISSUES[task.id])
    result, devices, initial = _match(world, task)
    reachies = [devices[d] for p in result.processes for d in p.devices if devices[d].driver == "reachy"]
    if reachies and all(starts_awake(config.sim) for config in reachies):
        request.getfixturevalue("shared_reachy")
    replies = [result.reply, *_kernel_answers(devices, initial, task)]
    for process in result.processes:
        [device] = process.devices
        output, state = await _run(process.summary, process.plan, device, devices[device], tmp_path)
        replies.append(output)
        problems = device_differences(task.expect.get(device, {}), initial[device], state, device)
        assert not problems, f"{task.said!r} on {device}: {[str(p) for p in problems]}"
    if task.reply is not None:
        assert reply_matches(task.reply, replies), f"no reply matches {task.reply!r}: {replies}"


@pytest.mark.parametrize("world", _conversation_files())
async def test_bench_conversations_run_on_one_kernel_per_file(world: TaskFile, tmp_path: Path) -> None:
    """Each conversation of the file passes on the file's kernel (a kernel per file, not per task:
    a start is seconds; ``rosaos bench`` shares one the same way)."""
    conversations = [
        task for task in world.tasks if _is_conversation(task) and task.id not in TASK_FILE_ISSUES
    ]
    uncovered = {task.id: reason for task in conversations if (reason := _covered(world, task, REGISTRY))}
    held = [task for task in conversations if task.id not in uncovered]
    if not held:
        pytest.skip(f"no conversation of {world.name} can be held to the offline engine yet: {uncovered}")
    failures = await _converse(world, held, tmp_path)
    assert not failures, f"{len(failures)} of {len(held)} conversations failed:\n" + "\n".join(
        f"{task_id}: {why}" for task_id, why in failures.items()
    )
