"""What the offline engine makes of every task sentence, one canonical JSON line each.

A speed change to the engine must not change one outcome. This script is the check: run it
before the change, keep its output, run it after, and ``diff`` the two files; the diff must be
empty. For each task file (every ``*.yaml`` of the folders or files given with ``--tasks``,
repeatable; by default the public ``../shared/bench/tasks``, ``benchmarks/tasks`` and
``benchmarks/tasks/fresh``) it builds the engine on that file's own world, as
``benchmarks/local_intent.py`` does, and writes for every sentence (each turn of a conversation
too) what :meth:`~rosaos.intents.understanding.matching.IntentMatcher.match` returns (kind, plans
and their steps, reply, suggestion, refusal) and what the kernel's own readers make of it
(:func:`read_stop`, :func:`read_question`, :func:`read_small_talk`), with sorted keys::

    .venv/bin/python benchmarks/match_outcomes.py --out /tmp/before.jsonl
    # change the engine
    .venv/bin/python benchmarks/match_outcomes.py --out /tmp/after.jsonl
    diff /tmp/before.jsonl /tmp/after.jsonl   # must print nothing

The script runs itself with ``PYTHONHASHSEED=0``: the fuzzy model's scores are float sums over
word sets, whose order (and so the last bits of a sum, and which of two equal guesses wins) depends
on the per-process hash seed, so one "Did you mean …?" suggestion could differ from run to run on
the same code.

Each sentence is matched twice, with the clause cache cleared before the first and kept for the
second, and both are written: a cache must not change an outcome either.
"""

from __future__ import annotations

import argparse
import dataclasses
import enum
import json
import os
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel

from rosaos.intents.grammar.vocabulary import sources_from_config
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.intents.understanding.questions import read_question
from rosaos.intents.understanding.small_talk import read_small_talk
from rosaos.intents.understanding.stop_words import DeviceRefs, read_stop
from rosaos.plugins import load_drivers

sys.path.insert(0, str(Path(__file__).resolve().parent))
from local_intent import world_devices

HERE = Path(__file__).resolve().parent
DEFAULT_TASKS = [HERE.parents[1] / "shared" / "bench" / "tasks", HERE / "tasks", HERE / "tasks" / "fresh"]


def plain(value: Any) -> Any:
    """``value`` as JSON-able data with a stable order (sets sorted, objects as their fields)."""
    if isinstance(value, BaseModel):
        return plain(value.model_dump(mode="json"))
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = {field.name: getattr(value, field.name) for field in dataclasses.fields(value)}
        return {"__type__": type(value).__name__, **plain(fields)}
    if isinstance(value, dict):
        return {str(key): plain(item) for key, item in value.items()}
    if isinstance(value, (set, frozenset)):
        return sorted((plain(item) for item in value), key=lambda item: json.dumps(item, sort_keys=True))
    if isinstance(value, (list, tuple)):
        return [plain(item) for item in value]
    if isinstance(value, enum.Enum):
        return plain(value.value)
    if value is None or isinstance(value, (str, int, float, bool)):
        return value
    return repr(value)


def sentences(task: dict[str, Any]) -> Iterator[str]:
    """Every sentence a task says: its ``say``, or each turn of a conversation."""
    said = task["say"]
    if isinstance(said, str):
        yield said
        return
    for turn in said:
        yield turn if isinstance(turn, str) else turn["text"]


def outcomes(paths: list[Path], language: str) -> Iterator[dict[str, Any]]:
    """One record per sentence of every file in ``paths``, each on its own file's world."""
    registry = load_drivers()
    for path in paths:
        document = yaml.safe_load(path.read_text(encoding="utf-8"))
        devices = world_devices(document["world"])
        matcher = IntentMatcher(sources_from_config(devices, registry), language)
        refs = DeviceRefs(sources_from_config(devices, registry), language)
        for task in document["tasks"]:
            for index, said in enumerate(sentences(task)):
                matcher.clear_cache()
                cold = plain(matcher.match(said))
                warm = plain(matcher.match(said))
                yield {
                    "file": path.name,
                    "task": task["id"],
                    "turn": index,
                    "say": said,
                    "match": cold,
                    "match_cached_same": cold == warm,
                    "stop": plain(read_stop(said, refs)),
                    "question": plain(read_question(said, refs)),
                    "small_talk": plain(
                        read_small_talk(said, lambda word, refs=refs: refs.resolve(word) is not None)
                    ),
                }


def main() -> None:
    """Write the outcomes of every sentence as JSON lines."""
    if os.environ.get("PYTHONHASHSEED") != "0":  # one set order for every run (module docstring)
        os.execve(sys.executable, [sys.executable, *sys.argv], {**os.environ, "PYTHONHASHSEED": "0"})
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--tasks", type=Path, action="append", help="task folder or file (repeatable; default: all three)"
    )
    parser.add_argument("--language", default="en")
    parser.add_argument("--out", type=Path, help="file to write (default: standard output)")
    options = parser.parse_args()
    folders = options.tasks or DEFAULT_TASKS
    paths = [
        path
        for folder in folders
        for path in (sorted(folder.glob("*.yaml")) if folder.is_dir() else [folder])
    ]
    lines = [
        json.dumps(record, sort_keys=True, ensure_ascii=False) for record in outcomes(paths, options.language)
    ]
    text = "\n".join(lines) + "\n"
    if options.out is None:
        sys.stdout.write(text)
    else:
        options.out.write_text(text, encoding="utf-8")
        print(f"{len(lines)} sentences from {len(paths)} files -> {options.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
