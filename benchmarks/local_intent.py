"""Micro-benchmark: how long the offline local-intent engine takes to match one sentence.

Runs every ``say:`` sentence of the public task files (``../shared/bench/tasks/*.yaml``, or the
folders or files given with ``--tasks``, repeatable) through :meth:`rosaos.intents.understanding.matching.IntentMatcher.match` against
its own world, with the installed drivers' intents. Each sentence is matched once to warm up, then
``--repeat`` times with the match cache cleared, so every timing is a full recognition.

Prints a table (per sentence: outcome, p50, p95) and then one JSON object with the totals::

    .venv/bin/python benchmarks/local_intent.py [--repeat 50] [--language en] [--tasks DIR_OR_FILE ...]

The slowest sentences are the ones no template spells out: they go through rephrasing and the
fuzzy model (:mod:`rosaos.intents.understanding.generalize`) after the literal reading fails, so the table also
gives p95 over the sentences that were not exact matches.

``--as-kernel`` times what the offline kernel does with a typed sentence instead: the stop and
state-question readers first (:func:`rosaos.models.kernel_actions.handles`), and the matcher only
for a sentence they do not answer. A question the kernel answers from state never reaches the
matcher, so matching it alone measures work no user waits for.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path
from typing import Any

import yaml

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.vocabulary import sources_from_config
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.intents.understanding.stop_words import DeviceRefs
from rosaos.models.kernel_actions import handles
from rosaos.plugins import load_drivers

DEFAULT_TASKS = Path(__file__).resolve().parents[2] / "shared" / "bench" / "tasks"


def world_devices(world: dict[str, Any]) -> dict[str, DeviceConfig]:
    """A task file's ``world:`` as ``[devices.*]`` tables; matching needs no state, so it is left out."""
    return {
        name: DeviceConfig(
            driver=entry["driver"],
            description=entry.get("description"),
            aliases=entry.get("aliases", []),
            area=entry.get("area"),
            sim=entry.get("sim", {}),
        )
        for name, entry in world.items()
    }


def percentile(samples: list[float], fraction: float) -> float:
    ordered = sorted(samples)
    return ordered[min(len(ordered) - 1, round(fraction * (len(ordered) - 1)))]


def main() -> None:
    """Run the benchmark and print the table and the JSON summary."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", type=Path, action="append", help="task folder or file (repeatable)")
    parser.add_argument("--repeat", type=int, default=50)
    parser.add_argument("--language", default="en")
    parser.add_argument(
        "--clock",
        choices=["wall", "cpu"],
        default="wall",
        help="wall: elapsed time (the default); cpu: this thread's CPU time, which other work on a "
        "busy machine does not inflate (the engine does no I/O, so on an idle machine both agree)",
    )
    parser.add_argument(
        "--as-kernel",
        action="store_true",
        help="time the kernel's order: the stop and question readers, then the matcher only for "
        "what they do not answer",
    )
    options = parser.parse_args()
    clock = time.thread_time if options.clock == "cpu" else time.perf_counter

    registry = load_drivers()
    rows: list[dict[str, Any]] = []
    build_ms: list[float] = []
    folders = options.tasks or [DEFAULT_TASKS]
    paths = [
        path
        for folder in folders
        for path in (sorted(folder.glob("*.yaml")) if folder.is_dir() else [folder])
    ]
    for path in paths:
        document = yaml.safe_load(path.read_text(encoding="utf-8"))
        started = time.perf_counter()
        matcher = IntentMatcher(
            sources_from_config(world_devices(document["world"]), registry), options.language
        )
        build_ms.append((time.perf_counter() - started) * 1000)
        refs = DeviceRefs(sources_from_config(world_devices(document["world"]), registry), options.language)

        def read(said: str, matcher: IntentMatcher = matcher, refs: DeviceRefs = refs) -> None:
            if not (options.as_kernel and handles(said, refs)):
                matcher.match(said)

        for task in document["tasks"]:
            if not isinstance(task["say"], str):  # a conversation: its first sentence
                first = task["say"][0]
                task = {**task, "say": first if isinstance(first, str) else first["text"]}
            outcome = matcher.match(task["say"])  # warm-up: hassil compiles lazily
            answered = options.as_kernel and handles(task["say"], refs)
            samples = []
            for _ in range(options.repeat):
                matcher.clear_cache()
                started = clock()
                read(task["say"])
                samples.append((clock() - started) * 1000)
            rows.append(
                {
                    "task": task["id"],
                    "say": task["say"],
                    "outcome": "kernel" if answered else outcome.kind,
                    "processes": len(outcome.processes),
                    "p50_ms": percentile(samples, 0.5),
                    "p95_ms": percentile(samples, 0.95),
                    "samples": samples,
                }
            )

    width = max(len(row["say"]) for row in rows)
    print(f"{'sentence':<{width}}  {'outcome':<9} {'procs':>5} {'p50 ms':>8} {'p95 ms':>8}")
    for row in rows:
        print(
            f"{row['say']:<{width}}  {row['outcome']:<9} {row['processes']:>5} "
            f"{row['p50_ms']:>8.2f} {row['p95_ms']:>8.2f}"
        )
    every = [sample for row in rows for sample in row["samples"]]
    exact = [sample for row in rows if row["outcome"] == "plans" for sample in row["samples"]]
    other = [sample for row in rows if row["outcome"] != "plans" for sample in row["samples"]]
    summary = {
        "sentences": len(rows),
        "repeat": options.repeat,
        "language": options.language,
        "clock": options.clock,
        "as_kernel": options.as_kernel,
        "kernel_answered": sum(row["outcome"] == "kernel" for row in rows),
        "build_ms_max": round(max(build_ms), 2),
        "p50_ms": round(percentile(every, 0.5), 3),
        "p95_ms": round(percentile(every, 0.95), 3),
        "mean_ms": round(statistics.fmean(every), 3),
        "exact_matches": sum(row["outcome"] == "plans" for row in rows),
        "exact_p50_ms": round(percentile(exact, 0.5), 3) if exact else None,
        "exact_p95_ms": round(percentile(exact, 0.95), 3) if exact else None,
        "not_exact_p95_ms": round(percentile(other, 0.95), 3) if other else None,
    }
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
