"""``rosaos bench PATH...``: load task files, run them, print the table (or JSON), pick the exit code.

Exit codes: 0 when the run completed, whatever the score; 1 when ``--fail-under`` is given and
the success rate is below it; 2 for usage and configuration errors (no path, a bad task file, a
bad ``--model``), reported before anything runs.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import re
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from rosaos.bench.report import ProgressBar, print_report
from rosaos.bench.results import BenchResult, FileResult, Summary
from rosaos.bench.runner import BenchProgress, run_file, select_tasks
from rosaos.bench.tasks import TaskFileError, TaskSelection, find_task_files, load_task_files
from rosaos.cli.console import console as terminal
from rosaos.config import ConfigError, RosaosConfig, load_config
from rosaos.models.defaults import kernel_spec
from rosaos.models.select import ModelError, build_model
from rosaos.plugins import DriverRegistry, load_drivers

EXIT_BELOW_THRESHOLD = 1
EXIT_USAGE = 2
LOG_FILE = "bench.log"
NO_PATHS = (
    "rosaos bench: no task files given; pass a file or a directory of them, "
    "e.g. `rosaos bench ../shared/bench/tasks` or `rosaos bench my-tasks.yaml`"
)


def bench_command(
    paths: Sequence[Path],
    *,
    config_path: Path | None,
    models: dict[str, Any],
    repeat: int,
    patterns: Sequence[str],
    json_output: bool,
    out: Path | None,
    fail_under: float | None,
) -> int:
    """Run the benchmark and report it; returns the exit code."""
    err = terminal(stderr=True)
    if not paths:
        err.print(NO_PATHS, markup=False)
        return EXIT_USAGE
    try:
        files = load_task_files(find_task_files(paths))
        selections = select_tasks(files, patterns)
        if not selections:
            ids = ", ".join(task.id for f in files for task in f.tasks)
            raise TaskFileError(f"no task id matches --tasks {' '.join(patterns)}; the ids are: {ids}")
        config = load_config(config_path, **({"models": models} if models else {}))
        spec = kernel_spec(config)
        if spec.model is not None:
            build_model(spec)  # a bad --model is a usage error now, not one failure per file later
    except (TaskFileError, ConfigError, ModelError) as error:
        err.print(f"rosaos bench: {error}", markup=False)
        return EXIT_USAGE
    registry = load_drivers()
    for broken in registry.broken:
        err.print(
            f"warning: plugin {broken.plugin} ({broken.package}) is broken: {broken.error}", markup=False
        )
    run_dir = _run_dir()
    description = (
        "offline local-intent engine"
        if spec.model is None
        else f"{spec.describe()} (prefer_local = {str(spec.prefer_local).lower()})"
    )
    total = sum(len(selection.tasks) for selection in selections) * repeat
    with (
        _logging_to(run_dir / LOG_FILE),
        _stdout_to(run_dir / LOG_FILE),
        ProgressBar(err, total, repeat) as progress,
    ):
        result = asyncio.run(run_bench(selections, config, registry, repeat, progress, run_dir, description))
    if out is not None:
        out.write_text(result.model_dump_json(indent=2) + "\n", encoding="utf-8")
    if json_output:
        print(result.model_dump_json(indent=2))
    else:
        print_report(result, terminal())
    rate = result.summary.success_rate
    if fail_under is not None and rate is not None and rate < fail_under:
        err.print(
            f"rosaos bench: success rate {rate:.1%} is below --fail-under {fail_under:.1%}", markup=False
        )
        return EXIT_BELOW_THRESHOLD
    return 0


async def run_bench(
    selections: Sequence[TaskSelection],
    config: RosaosConfig,
    registry: DriverRegistry,
    repeat: int,
    progress: BenchProgress,
    run_dir: Path,
    model: str,
) -> BenchResult:
    """Run every selected file, each on a fresh kernel with its own data directory under ``run_dir``."""
    started, clock = datetime.now(UTC), time.monotonic()
    results: list[FileResult] = []
    for index, selection in enumerate(selections, 1):
        slug = re.sub(r"[^A-Za-z0-9_.-]+", "-", selection.file.name)
        # devices cleared: a file's world comes from the task file, never from rosaos.toml.
        file_config = config.model_copy(update={"data_dir": run_dir / f"{index:02d}-{slug}", "devices": {}})
        results.append(await run_file(selection, file_config, registry, repeat, progress))
    return BenchResult(
        model=model,
        repeat=repeat,
        started_at=started,
        duration_s=round(time.monotonic() - clock, 3),
        data_dir=str(run_dir),
        files=results,
        summary=Summary.of([task for file in results for task in file.tasks]),
    )


def _run_dir() -> Path:
    """A fresh directory for this run: under ``$ROSAOS_DATA_DIR/bench`` if set, else a temp dir.

    Never the user's own data directory: a run must not touch the event store of their rosaOS.
    """
    base = os.environ.get("ROSAOS_DATA_DIR")
    if base:
        parent = Path(base) / "bench"
        parent.mkdir(parents=True, exist_ok=True)
        return Path(tempfile.mkdtemp(prefix=datetime.now().strftime("%Y%m%d-%H%M%S-"), dir=parent))
    return Path(tempfile.mkdtemp(prefix="rosaos-bench-"))


@contextlib.contextmanager
def _stdout_to(path: Path) -> Iterator[None]:
    """Send whatever the run prints to stdout into ``path``: the table and the JSON own stdout.

    The simulators run in this process, and some libraries print to stdout.
    Redirected at the file descriptor too, so threads and child programs are covered.
    """
    sys.stdout.flush()
    saved = os.dup(1)
    with path.open("a", encoding="utf-8") as sink:
        os.dup2(sink.fileno(), 1)
        try:
            with contextlib.redirect_stdout(sink):
                yield
        finally:
            sink.flush()
            os.dup2(saved, 1)
            os.close(saved)


@contextlib.contextmanager
def _logging_to(path: Path) -> Iterator[None]:
    """Send warnings (a simulator that would not start, a kernel model failure) to the run's log
    instead of the terminal, where they would break the progress bar; restore logging after."""
    root = logging.getLogger()
    saved = (root.handlers[:], root.level)
    handler = logging.FileHandler(path, encoding="utf-8")
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
    root.handlers[:] = [handler]
    root.setLevel(logging.WARNING)
    try:
        yield
    finally:
        root.handlers[:], level = saved
        root.setLevel(level)
        handler.close()
