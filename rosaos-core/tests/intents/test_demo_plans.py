"""The paper's demonstration (``../shared/bench/demo``), planned offline: every sentence is understood.

Fast and generic (nothing here knows a sentence): each thing a demo task says must be an exact
match, through the follow-up planner first as the kernel model does. A sentence that holds a
follow-up launches one process, whose plan carries the rest; a plan never holds two devices'
worth of steps that the sentence meant to run one after the other. ``rosaos bench`` runs the
demo itself on the simulators (see docs/bench.md for its 3/3 runs and latencies).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from rosaos.bench.sim_world import bench_world
from rosaos.bench.tasks import BenchTask, TaskFile, load_task_file
from rosaos.intents.grammar.vocabulary import device_vocabularies
from rosaos.intents.planning.follow_ups import plan_follow_up
from rosaos.models.kernel_model import LocalIntentModel
from rosaos.plugins import load_drivers

DEMO = Path(__file__).resolve().parents[3].parent / "shared" / "bench" / "demo"
REGISTRY = load_drivers()


def _tasks() -> list[Any]:
    if not DEMO.is_dir():
        return [
            pytest.param(None, None, marks=pytest.mark.skip(reason=f"{DEMO} is not next to this checkout"))
        ]
    return [
        pytest.param(task_file, task, id=task.id)
        for path in sorted(DEMO.glob("*.yaml"))
        for task_file in [load_task_file(path)]
        for task in task_file.tasks
    ]


@pytest.mark.parametrize(("task_file", "task"), _tasks())
def test_every_demo_sentence_is_planned(task_file: TaskFile, task: BenchTask) -> None:
    model = LocalIntentModel(device_vocabularies(bench_world(task_file, REGISTRY).world))
    for item in task.utterances:
        result = plan_follow_up(item.text, model.match) or model.match(item.text)
        assert result.is_exact, f"{item.text!r}: {result.reply}"
        for process in result.processes:
            if process.plan.then is not None:
                follow = {d for launch in process.plan.then.launches for d in launch.devices}
                assert not follow & set(process.devices), "a follow-up's devices are held by the first step"
