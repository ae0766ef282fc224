"""``rosaos up`` after its banner: devices are reported as they come up, then one last line.

With a few devices each gets a line; with many, a count. A device that fails is named with its
error. Once none is starting, the watch says how it ended and stops.
"""

from __future__ import annotations

import asyncio
import io
import time
from collections.abc import Iterator

from rich.console import Console

from rosaos.cli.up_progress import ONE_LINE_EACH, report_devices
from rosaos.devices.directory import DirectoryEntry
from rosaos.devices.run_files import DeviceStatus


def entry(name: str, status: DeviceStatus, error: str | None = None) -> DirectoryEntry:
    url = f"http://127.0.0.1:1/{name}/mcp" if status == "healthy" else None
    return DirectoryEntry(
        name=name, driver="tapo", url=url, token="t", status=status, remote=False, error=error
    )


class Steps:
    """A directory that changes at each look: ``steps[i]`` is what the i-th look sees (the last repeats)."""

    def __init__(self, steps: list[dict[str, DeviceStatus]], errors: dict[str, str] | None = None) -> None:
        self._steps: Iterator[dict[str, DeviceStatus]] = iter(steps)
        self._last = steps[0]
        self._errors = errors or {}

    def __call__(self) -> dict[str, DirectoryEntry]:
        self._last = next(self._steps, self._last)
        return {name: entry(name, status, self._errors.get(name)) for name, status in self._last.items()}


def run(directory: Steps) -> list[str]:
    out = io.StringIO()
    asyncio.run(report_devices(directory, Console(file=out, width=200), time.monotonic(), poll=0.0))
    return out.getvalue().splitlines()


def test_a_few_devices_get_a_line_each_as_they_come_up_then_all_healthy() -> None:
    lines = run(
        Steps(
            [
                {"lamp": "starting", "fan": "starting"},
                {"lamp": "starting", "fan": "starting"},
                {"lamp": "healthy", "fan": "starting"},
                {"lamp": "healthy", "fan": "healthy"},
            ]
        )
    )
    assert [line.split()[:3] for line in lines[:2]] == [
        ["Device:", "lamp", "healthy"],
        ["Device:", "fan", "healthy"],
    ]
    assert lines[2].startswith("All 2 devices are healthy (")
    assert len(lines) == 3


def test_many_devices_are_counted_and_a_failed_one_is_named_with_its_error() -> None:
    names = [f"lamp_{k}" for k in range(ONE_LINE_EACH + 8)]
    starting: dict[str, DeviceStatus] = dict.fromkeys(names, "starting")
    half: dict[str, DeviceStatus] = {**starting, **dict.fromkeys(names[:10], "healthy")}
    done: dict[str, DeviceStatus] = {**dict.fromkeys(names, "healthy"), "lamp_3": "failed"}
    lines = run(Steps([starting, half, done], errors={"lamp_3": "port 9 is taken"}))
    assert "  Device:    lamp_3 is failed: port 9 is taken" in lines
    assert not any(line.startswith("  Device:    lamp_0 ") for line in lines)  # counted, not listed
    assert lines[-1].startswith("Devices settled ")
    assert f"{len(names) - 1} of {len(names)} healthy" in lines[-1]
    assert "rosaos devices list" in lines[-1]
