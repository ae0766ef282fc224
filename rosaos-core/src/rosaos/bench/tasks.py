"""Task files of the task-success benchmark: the format as pydantic models, and loading them.

The format is specified in ``../shared/bench/README.md``: a file names a simulated ``world``
(device instances with their initial ``state`` and sim-only ``sim`` settings) and the ``tasks`` to
run in it (``say``, optional ``setup``, ``expect``, optional ``reply``).

Every problem is reported as ``<file>: <key path>: <reason>`` (e.g.
``home.yaml: tasks[3] (home-pause).expect.spotfy: unknown device ...``), and all problems of all
files are reported together, so a broken file is fixed in one go.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, field_validator

OPERATORS = ("gt", "lt", "between", "contains", "changed")
"""The operators an ``expect`` value may use instead of a plain value."""

TASK_FILE_SUFFIXES = (".yaml", ".yml")


class TaskFileError(Exception):
    """Task files that cannot be used. One line per problem: ``file: key: reason``."""


class _TaskYamlLoader(yaml.SafeLoader):
    """YAML with YAML 1.2 booleans: only ``true``/``false``.

    PyYAML follows YAML 1.1, where ``on``, ``off``, ``yes`` and ``no`` are booleans too. Task files
    write ``{on: true}`` (the Tapo key) and ``repeat: off`` (the Spotify value): both must stay
    strings.
    """


_BOOL_TAG = "tag:yaml.org,2002:bool"
_TaskYamlLoader.yaml_implicit_resolvers = {
    first: [(tag, pattern) for tag, pattern in resolvers if tag != _BOOL_TAG]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_TaskYamlLoader.add_implicit_resolver(
    _BOOL_TAG, re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")
)


class WorldDevice(BaseModel):
    """One device instance of a task world, by the name the kernel sees."""

    model_config = ConfigDict(extra="forbid")

    driver: str = Field(min_length=1, description="Entry-point name of the driver: tapo, spotify, ros...")
    description: str | None = None
    state: dict[str, Any] = Field(default_factory=dict)
    """Initial simulator state, keys as ``get_state`` returns them; checked by "nothing else moves"."""
    sim: dict[str, Any] = Field(default_factory=dict)
    """Simulator-only settings (a music catalog, a ros ``profile``); never compared."""


SETTLE_DEFAULT = 60.0
"""Seconds a task may take to settle unless it says otherwise (``settle``)."""
SETTLE_MAX = 600.0


class SayItem(BaseModel):
    """One thing said in a conversation task: the text, and how long after the item before it."""

    model_config = ConfigDict(extra="forbid")

    text: str = Field(min_length=1, max_length=4000)
    after: float = Field(default=0.0, ge=0.0, le=SETTLE_MAX)
    """Seconds after the item before it was accepted; 0 posts it at once."""


class BenchTask(BaseModel):
    """One sentence (or a conversation) to say in the world, and the state it must leave behind."""

    model_config = ConfigDict(extra="forbid")

    id: str = Field(min_length=1, max_length=200)
    say: str | list[str | SayItem] = Field(min_length=1)
    """A sentence, or a list of them posted one by one (an item may wait ``after`` seconds)."""
    settle: float = Field(default=SETTLE_DEFAULT, gt=0, le=SETTLE_MAX)
    """Seconds from the first post before an unsettled task fails."""
    setup: dict[str, dict[str, Any]] = Field(default_factory=dict)
    """Per-task overrides of the initial state: ``{device: {key: value}}``."""
    expect: dict[str, dict[str, Any]]
    """The state after settling; ``{}`` means "change nothing"."""
    reply: str | None = None
    """A regex that some reply to the user must match."""

    @field_validator("say")
    @classmethod
    def _sentences(cls, value: str | list[str | SayItem]) -> str | list[str | SayItem]:
        for item in [value] if isinstance(value, str) else value:
            text = item if isinstance(item, str) else item.text
            if not text.strip() or len(text) > 4000:
                raise ValueError("each thing said must be 1 to 4000 characters, not blank")
        return value

    @property
    def utterances(self) -> list[SayItem]:
        """What is said, in order, each with its delay."""
        items = [self.say] if isinstance(self.say, str) else self.say
        return [SayItem(text=item) if isinstance(item, str) else item for item in items]

    @property
    def said(self) -> str:
        """Everything said, on one line (for reports)."""
        return " / ".join(item.text for item in self.utterances)

    @field_validator("reply")
    @classmethod
    def _compiles(cls, value: str | None) -> str | None:
        if value is not None:
            try:
                re.compile(value)
            except re.error as error:
                raise ValueError(f"not a valid regular expression: {error}") from None
        return value


class TaskFile(BaseModel):
    """A whole task file: its world and its tasks."""

    model_config = ConfigDict(extra="forbid")

    name: str = Field(min_length=1)
    world: dict[str, WorldDevice] = Field(min_length=1)
    tasks: list[BenchTask] = Field(min_length=1)
    _path: Path = PrivateAttr(default=Path("-"))

    @property
    def path(self) -> Path:
        """The file it was loaded from."""
        return self._path

    def initial_state(self, task: BenchTask) -> dict[str, dict[str, Any]]:
        """Every device's initial ``state`` with the task's ``setup`` applied, key by key."""
        return {name: {**device.state, **task.setup.get(name, {})} for name, device in self.world.items()}


@dataclass(frozen=True)
class TaskSelection:
    """The tasks of one file that a run takes (all of them, or those ``--tasks`` matches)."""

    file: TaskFile
    tasks: list[BenchTask]


def find_task_files(paths: Iterable[Path]) -> list[Path]:
    """The task files named by ``paths``: files as given, directories by their ``*.yaml``/``*.yml``."""
    found: list[Path] = []
    missing: list[str] = []
    for path in paths:
        if path.is_dir():
            inside = sorted(p for p in path.iterdir() if p.is_file() and p.suffix in TASK_FILE_SUFFIXES)
            if not inside:
                missing.append(f"{path}: no task files (*.yaml) in this directory")
            found += inside
        elif path.is_file():
            found.append(path)
        else:
            missing.append(f"{path}: no such file or directory")
    if missing:
        raise TaskFileError("\n".join(missing))
    return list(dict.fromkeys(found))


def load_task_files(paths: Sequence[Path]) -> list[TaskFile]:
    """Load and check every file; raise :class:`TaskFileError` listing every problem in all of them.

    Besides each file on its own, task ids must be unique across all files.
    """
    files: list[TaskFile] = []
    problems: list[str] = []
    for path in paths:
        try:
            files.append(load_task_file(path))
        except TaskFileError as error:
            problems.append(str(error))
    seen: dict[str, Path] = {}
    for task_file in files:
        for index, task in enumerate(task_file.tasks):
            if task.id in seen and seen[task.id] != task_file.path:
                problems.append(
                    f"{task_file.path}: {_task_key(index, task.id)}.id: {task.id!r} is already used in "
                    f"{seen[task.id]}; task ids must be unique across all files"
                )
            seen.setdefault(task.id, task_file.path)
    if problems:
        raise TaskFileError("\n".join(problems))
    return files


def load_task_file(path: Path) -> TaskFile:
    """Read and validate one task file; :class:`TaskFileError` names the file and the key."""
    try:
        document = yaml.load(path.read_text(encoding="utf-8"), Loader=_TaskYamlLoader)
    except OSError as error:
        raise TaskFileError(f"{path}: cannot read: {error.strerror}") from None
    except yaml.YAMLError as error:
        raise TaskFileError(f"{path}: not valid YAML: {error}") from None
    if not isinstance(document, dict):
        raise TaskFileError(f"{path}: a task file is a mapping with name, world and tasks (see the README)")
    try:
        task_file = TaskFile.model_validate(document)
    except ValidationError as error:
        raise TaskFileError(_validation_problems(path, error, document)) from None
    task_file._path = path
    problems = _reference_problems(task_file)
    if problems:
        raise TaskFileError("\n".join(f"{path}: {problem}" for problem in problems))
    return task_file


def _reference_problems(task_file: TaskFile) -> list[str]:
    """What pydantic cannot see: unknown devices, duplicate ids, malformed operators."""
    problems: list[str] = []
    known = ", ".join(task_file.world)
    ids: set[str] = set()
    for index, task in enumerate(task_file.tasks):
        where = _task_key(index, task.id)
        if task.id in ids:
            problems.append(f"{where}.id: {task.id!r} appears twice in this file; ids must be unique")
        ids.add(task.id)
        for section, devices in (("setup", task.setup), ("expect", task.expect)):
            for device, values in devices.items():
                if device not in task_file.world:
                    problems.append(
                        f"{where}.{section}.{device}: unknown device; devices in this world: {known}"
                    )
                if section == "expect":
                    problems += [f"{where}.expect.{device}.{p}" for p in expect_value_problems(values)]
    return problems


def expect_value_problems(values: Mapping[str, Any]) -> list[str]:
    """Malformed operators in one device's ``expect``, as ``key: reason``; nested dicts recurse."""
    problems: list[str] = []
    for key, want in values.items():
        if not isinstance(want, dict):
            continue
        operators = [name for name in want if name in OPERATORS]
        if not operators:
            problems += [f"{key}.{p}" for p in expect_value_problems(want)]
        elif len(want) > 1:
            problems.append(
                f"{key}: an operator stands alone ({{{operators[0]}: ...}}); "
                f"got keys {', '.join(map(str, want))}"
            )
        else:
            reason = _operand_problem(operators[0], want[operators[0]])
            if reason:
                problems.append(f"{key}.{operators[0]}: {reason}")
    return problems


def _operand_problem(operator: str, operand: Any) -> str | None:
    def number(value: Any) -> bool:
        return isinstance(value, int | float) and not isinstance(value, bool)

    if operator in ("gt", "lt") and not number(operand):
        return f"needs a number, e.g. {{{operator}: 0.5}}; got {operand!r}"
    if operator == "between":
        if not (isinstance(operand, list) and len(operand) == 2 and all(map(number, operand))):
            return f"needs [low, high], two numbers; got {operand!r}"
        if operand[0] > operand[1]:
            return f"needs low <= high; got {operand!r}"
    if operator == "contains" and not isinstance(operand, str):
        return f"needs text, e.g. {{contains: jazz}}; got {operand!r}"
    if operator == "changed" and not isinstance(operand, bool):
        return f"needs true or false; got {operand!r}"
    return None


def _task_key(index: int, task_id: str | None) -> str:
    return f"tasks[{index}] ({task_id})" if task_id else f"tasks[{index}]"


def _validation_problems(path: Path, error: ValidationError, document: dict[str, Any]) -> str:
    """pydantic's errors as ``file: tasks[3] (id).key: reason`` lines."""
    lines = []
    for problem in error.errors():
        loc = list(problem["loc"])
        parts: list[str] = []
        if len(loc) >= 2 and loc[0] == "tasks" and isinstance(loc[1], int):
            tasks = document.get("tasks")
            entry = tasks[loc[1]] if isinstance(tasks, list) and loc[1] < len(tasks) else None
            task_id = entry.get("id") if isinstance(entry, dict) else None
            parts.append(_task_key(loc[1], str(task_id) if task_id is not None else None))
            loc = loc[2:]
        parts += [str(part) for part in loc]
        key = ".".join(parts) or "(top level)"
        message = problem["msg"]
        if problem["type"] == "extra_forbidden":
            message = "unknown key (see the task file format in the bench README)"
        lines.append(f"{path}: {key}: {message}")
    return "\n".join(lines)
