"""``rosaos up`` after its banner: say which devices came up, until every one has settled.

The banner comes as soon as the kernel takes commands; a hundred simulated lamps are still
starting then. A person at the terminal wants to know when they are all there, and which one is
not. With a few devices each gets its own line as it comes up; with many, one count a second
("Devices: 56 of 100 healthy") keeps the terminal readable. A device that fails is always named,
with its error. Once none is starting any more, a last line says how it ended and the watch stops
(it costs nothing while rosaOS idles).
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable, Mapping

from rich.console import Console

from rosaos.devices.directory import DirectoryEntry

ONE_LINE_EACH = 12
"""Up to this many devices, each is reported on its own line; above it, a count."""
POLL = 0.25
"""Seconds between looks at the device directory."""
COUNT_EVERY = 1.0
"""Seconds between two count lines."""
SETTLING: frozenset[str] = frozenset({"starting", "restarting"})
"""Statuses of a device that has not had its first answer yet."""


def device_line(entry: DirectoryEntry) -> str:
    """One device as the banner lists it."""
    where = entry.url or "-"
    return f"  Device:    {entry.name:<20} {entry.status:<16} {where}"


async def report_devices(
    directory: Callable[[], Mapping[str, DirectoryEntry]],
    console: Console,
    started: float,
    poll: float = POLL,
) -> None:
    """Print devices as they come up (see the module docstring); return once none is starting."""
    shown: dict[str, str] = {name: entry.status for name, entry in directory().items()}
    many = len(shown) > ONE_LINE_EACH
    last_count = time.monotonic()
    counted = sum(1 for status in shown.values() if status == "healthy")  # the banner said so
    while True:
        entries = directory()
        settled = all(entry.status not in SETTLING for entry in entries.values())
        healthy = sum(1 for entry in entries.values() if entry.status == "healthy")
        for name, entry in entries.items():
            if shown.get(name) == entry.status:
                continue
            shown[name] = entry.status
            if entry.status in ("failed", "unhealthy", "unreachable"):
                console.print(
                    f"  Device:    {name} is {entry.status}: {entry.error or 'no reason given'}", markup=False
                )
            elif not many and entry.status not in SETTLING:
                console.print(device_line(entry), markup=False)
        now = time.monotonic()
        if many and not settled and healthy != counted and now - last_count >= COUNT_EVERY:
            console.print(f"  Devices:   {healthy} of {len(entries)} healthy", markup=False)
            counted, last_count = healthy, now
        if settled:
            console.print(_summary(entries, healthy, time.monotonic() - started), markup=False)
            return
        await asyncio.sleep(poll)


def _summary(entries: Mapping[str, DirectoryEntry], healthy: int, seconds: float) -> str:
    served = [entry for entry in entries.values() if entry.status != "not implemented"]
    if healthy == len(served):
        which = "The device is" if healthy == 1 else f"All {healthy} devices are"
        return f"{which} healthy ({seconds:.1f} s after start)."
    return (
        f"Devices settled {seconds:.1f} s after start: {healthy} of {len(served)} healthy; "
        "`rosaos devices list` says why the others are not."
    )
