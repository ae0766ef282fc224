"""Which device instances are being served on this machine, and where: the run files.

``rosaos up`` (the :class:`~rosaos.devices.supervisor.DeviceSupervisor`) writes
``<data_dir>/run/devices.json`` on every status change and removes it when it stops;
``rosaos serve-device`` records its one instance in ``<data_dir>/run/serve-device/<name>.json``.
``rosaos devices list`` and ``rosaos devices check`` read them through :func:`served_devices`, which
ignores files left behind by a process that died, and :func:`devices_not_ready`, which says what
``rosaos up`` is still starting.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path
from typing import Literal

from pydantic import BaseModel, Field, ValidationError

DeviceStatus = Literal[
    "starting", "healthy", "unhealthy", "restarting", "failed", "unreachable", "not implemented", "stopped"
]
"""Where an instance stands. ``failed``: its host could not start (retried with backoff);
``restarting``: its host died or stopped answering and is being replaced; ``unreachable``: a remote
instance that does not answer; ``not implemented``: a placeholder driver, listed but never served."""


class RunFileEntry(BaseModel):
    """One served instance as `run/devices.json` records it for other commands (no token; the host's pid)."""

    url: str | None
    pid: int | None
    status: DeviceStatus
    since: datetime
    error: str | None = None
    restarts: int = 0


class RunFile(BaseModel):
    """``<data_dir>/run/devices.json``: written by the supervisor on every status change."""

    supervisor_pid: int
    devices: dict[str, RunFileEntry] = Field(default_factory=dict)


def run_file_path(data_dir: Path) -> Path:
    """Where the supervisor records the instances it serves."""
    return data_dir / "run" / "devices.json"


def _serve_device_dir(data_dir: Path) -> Path:
    return data_dir / "run" / "serve-device"


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` (owner-only) so readers see the old file or the new, never half."""
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(fd, "w", encoding="utf-8") as handle:
        handle.write(text)
    os.replace(tmp, path)


def pid_alive(pid: int) -> bool:
    """Whether a process with this pid exists: how stale run files are recognised."""
    if pid <= 0:  # 0 and negatives address process groups, not one process
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, owned by someone else
        return True
    return True


def read_runtime_file(data_dir: Path) -> RunFile | None:
    """The supervisor's run file, or None when absent, unreadable or left by a dead supervisor."""
    try:
        runtime = RunFile.model_validate_json(run_file_path(data_dir).read_text(encoding="utf-8"))
    except (OSError, ValidationError):
        return None
    return runtime if pid_alive(runtime.supervisor_pid) else None


def served_devices(data_dir: Path) -> dict[str, RunFileEntry]:
    """Instances being served on this machine (by ``rosaos up`` or ``rosaos serve-device``), by name."""
    served: dict[str, RunFileEntry] = {}
    runtime = read_runtime_file(data_dir)
    if runtime is not None:
        served.update({n: e for n, e in runtime.devices.items() if e.url and e.pid and pid_alive(e.pid)})
    with contextlib.suppress(OSError):
        for path in sorted(_serve_device_dir(data_dir).glob("*.json")):
            try:
                entry = RunFileEntry.model_validate_json(path.read_text(encoding="utf-8"))
            except (OSError, ValidationError):
                continue
            if entry.url and entry.pid and pid_alive(entry.pid):
                served.setdefault(path.stem, entry)
    return served


def devices_not_ready(data_dir: Path) -> dict[str, RunFileEntry]:
    """Instances a running ``rosaos up`` hosts but does not serve yet (starting, restarting, failed), by name.

    ``rosaos up`` owns them: a command that wants one waits for it rather than starting a second copy.
    """
    runtime = read_runtime_file(data_dir)
    if runtime is None:
        return {}
    return {
        name: entry
        for name, entry in runtime.devices.items()
        if entry.status != "stopped" and not (entry.url and entry.pid and pid_alive(entry.pid))
    }


@contextlib.contextmanager
def record_served_device(data_dir: Path, name: str, url: str) -> Iterator[None]:
    """Record a ``rosaos serve-device`` instance for the block's duration, so ``devices check`` finds it."""
    path = _serve_device_dir(data_dir) / f"{name}.json"
    entry = RunFileEntry(url=url, pid=os.getpid(), status="healthy", since=now())
    write_atomic(path, entry.model_dump_json(indent=2))
    try:
        yield
    finally:
        path.unlink(missing_ok=True)


def now() -> datetime:
    """The current time, timezone-aware (UTC), as run files record it."""
    return datetime.now(UTC)
