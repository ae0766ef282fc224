"""The kernel's work per command does not grow with the number of devices (issue 27, part 3).

At 300 lamps the kernel spent twice the CPU per command it spent at 100: something in its
handling of each event walked every device. This counts work, not time (timing would flake on a
busy machine): the Python function calls the kernel's own code makes (the kernel, the offline
engine's models and intents, process management, events, memory) while a burst of commands is
handled, from the POST to every process's end, with the lamps served by a real shared host. The
count per command at many lamps must stay within a few percent of the count at a few.
"""

from __future__ import annotations

import asyncio
import cProfile
import pstats
import uuid
from pathlib import Path
from typing import Any

import pytest

from rosaos.auth import load_or_create_token
from rosaos.config import load_config
from rosaos.devices.supervisor import DeviceSupervisor
from rosaos.devices.world import build_world
from rosaos.kernel.runtime import Kernel
from rosaos.plugins import load_drivers

from .e2e_support import kernel_api, running_kernel

pytestmark = pytest.mark.slow

COMMANDS = 6
FEW, MANY = 10, 80
COUNTED = ("/rosaos/kernel/", "/rosaos/models/", "/rosaos/intents/", "/rosaos/processes/", "/rosaos/events/")
"""The kernel's own code; not the device servers, not the test's client, not the libraries (their
work follows from the kernel's calls, and their caches make it depend on what ran before)."""


def lamps(n: int) -> str:
    return "[kernel]\npool_size = 2\n" + "".join(
        f'[devices.lamp_{k}]\ndriver = "tapo"\ndescription = "Lamp {k}"\nsim = {{ on = false }}\n'
        for k in range(n)
    )


async def burst(kernel: Kernel, first: int, count: int) -> None:
    """``count`` "turn on lamp k" at once; returns when every process they launched has ended."""
    after = await kernel.parts.updates.last_id()
    async with kernel_api(kernel) as api:
        replies = await asyncio.gather(
            *(
                api.post(
                    "/chat",
                    json={"text": f"turn on lamp {k}"},
                    headers={"Idempotency-Key": str(uuid.uuid4())},
                )
                for k in range(first, first + count)
            )
        )
    assert [reply.status_code for reply in replies] == [202] * count
    ended = 0
    async with asyncio.timeout(60):
        async for update in kernel.parts.updates.follow(after):
            if update.kind == "process_ended":
                assert update.data.get("status") == "ok", update.text
                ended += 1
                if ended == count:
                    return


def kernel_calls(profile: cProfile.Profile) -> dict[str, int]:
    """Calls made into or by the kernel's own code, per called function.

    "By" counts a builtin or library function the kernel calls (``str.split`` in a loop over
    every device name), not what that library does inside."""
    counted: dict[str, int] = {}
    stats: dict[Any, Any] = pstats.Stats(profile).stats  # type: ignore[attr-defined]
    for (file, line, name), (_, _, _, _, callers) in stats.items():
        own = _ours(file)
        for caller, (_, calls, *_) in callers.items():
            if own or _ours(caller[0]):
                where = f"{file.replace(chr(92), '/').rsplit('/rosaos/', 1)[-1]}:{line}({name})"
                counted[where] = counted.get(where, 0) + calls
    return counted


def _ours(file: str) -> bool:
    return any(part in file.replace("\\", "/") for part in COUNTED)


async def calls_per_command(home: Path, n: int) -> dict[str, float]:
    home.mkdir()  # noqa: ASYNC240 (before anything runs)
    data_dir = home / "data"
    world_text = lamps(n)
    (home / "rosaos.toml").write_text(f'data_dir = "{data_dir}"\n' + world_text)
    world = build_world(load_config(home / "rosaos.toml"), load_drivers())
    supervisor = DeviceSupervisor(world, data_dir, load_or_create_token(data_dir), defer_background=True)
    async with running_kernel(home, world_text, devices=supervisor) as kernel:
        await burst(kernel, 0, 2)  # once before counting: first-use work (imports, caches) is not per event
        profile = cProfile.Profile()
        profile.enable()
        try:
            await burst(kernel, 2, COMMANDS)
        finally:
            profile.disable()
    return {where: calls / COMMANDS for where, calls in kernel_calls(profile).items()}


async def test_the_kernels_calls_per_command_do_not_grow_with_the_number_of_devices(tmp_path: Path) -> None:
    few = await calls_per_command(tmp_path / "few", FEW)
    many = await calls_per_command(tmp_path / "many", MANY)
    grown = sorted(((many.get(k, 0) - few.get(k, 0), k) for k in set(few) | set(many)), reverse=True)
    report = "\n".join(f"{delta:+9.1f}  {where}" for delta, where in grown[:15])
    total_few, total_many = sum(few.values()), sum(many.values())
    print(f"kernel calls per command: {total_few:.0f} at {FEW} lamps, {total_many:.0f} at {MANY}\n{report}")
    # 8 times the devices; a walk over them per event would add thousands of calls per command.
    assert total_many <= 1.05 * total_few + 200, f"grew from {total_few:.0f} to {total_many:.0f}:\n{report}"
