"""Simulated instances share one device host: one process, each instance its own URL, restarted together."""

from __future__ import annotations

import asyncio
import json
import os
import signal
from pathlib import Path
from typing import Any

import pytest

from rosaos.devices.client import DeviceClient
from rosaos.devices.run_files import run_file_path
from rosaos.devices.supervisor import DeviceSupervisor
from rosaos.plugins import load_drivers

from .devices_support import (
    HealthWitness,
    drivers_for_tests,
    eventually,
    pid_alive,
    plugin,
    requires_tapo,
    world_of,
)

TOKEN = "shared-host-test-token"
FAST: dict[str, Any] = {"health_interval": 0.2, "health_timeout": 2.0, "backoff_base": 0.1, "stop_grace": 2.0}

pytestmark = [pytest.mark.slow, pytest.mark.asyncio, requires_tapo]


def pids(data_dir: Path) -> dict[str, int | None]:
    devices = json.loads(run_file_path(data_dir).read_text())["devices"]
    return {name: entry["pid"] for name, entry in devices.items()}


async def test_sim_instances_share_one_host_and_keep_their_own_urls_and_state(data_dir: Path) -> None:
    world = world_of(
        drivers_for_tests(with_tapo=True),
        data_dir,
        kitchen_light={"driver": "tapo", "sim": {"on": False}},
        desk_lamp={"driver": "tapo", "sim": {"on": True}},
    )
    async with DeviceSupervisor(world, data_dir, TOKEN, **FAST) as supervisor:
        directory = supervisor.directory()
        assert {e.status for e in directory.values()} == {"healthy"}
        served = pids(data_dir)
        assert served["kitchen_light"] == served["desk_lamp"] != os.getpid()
        assert directory["kitchen_light"].url != directory["desk_lamp"].url
        light = DeviceClient(directory["kitchen_light"].url or "", TOKEN, 5.0, "kitchen_light")
        lamp = DeviceClient(directory["desk_lamp"].url or "", TOKEN, 5.0, "desk_lamp")
        await light.call("turn_on")
        assert (await light.get_state())["on"] is True
        await lamp.call("turn_off")
        assert (await lamp.get_state())["on"] is False
        assert (await light.get_state())["on"] is True  # one backend per instance, not one per host
        assert supervisor.log_file("shared-sims").is_file()


async def test_a_killed_shared_host_restarts_its_instances_and_says_so(data_dir: Path) -> None:
    world = world_of(
        drivers_for_tests(with_tapo=True),
        data_dir,
        kitchen_light={"driver": "tapo"},
        desk_lamp={"driver": "tapo"},
    )
    supervisor = DeviceSupervisor(world, data_dir, TOKEN, **FAST)
    witness = HealthWitness(supervisor)
    supervisor.on_status_change = witness
    async with supervisor:
        old_pid = pids(data_dir)["kitchen_light"]
        assert old_pid is not None
        urls = {name: e.url for name, e in supervisor.directory().items()}
        epochs = {name: e.server_epoch for name, e in supervisor.directory().items()}
        assert epochs == {"kitchen_light": f"pid-{old_pid}", "desk_lamp": f"pid-{old_pid}"}
        os.kill(old_pid, signal.SIGKILL)
        await eventually(
            lambda: all(e.status == "healthy" and e.restarts == 1 for e in supervisor.directory().values())
        )
        assert not pid_alive(old_pid)
        new = pids(data_dir)
        assert new["kitchen_light"] == new["desk_lamp"] not in (None, old_pid)
        assert {name: e.url for name, e in supervisor.directory().items()} == urls  # same ports again
        # ...but a new server, which knows no session a worker kept (processes/worker.py)
        assert {e.server_epoch for e in supervisor.directory().values()} == {f"pid-{new['kitchen_light']}"}
    changes = witness.changes
    for name in ("kitchen_light", "desk_lamp"):
        assert (name, "healthy", "restarting") in changes
        assert changes.index((name, "healthy", "restarting")) < max(
            i for i, change in enumerate(changes) if change[0] == name and change[2] == "healthy"
        )
    reported = [name for name, _, _ in witness.healthy]
    assert reported.count("kitchen_light") >= 2 and reported.count("desk_lamp") >= 2  # start, restart...
    assert witness.reported_before_recorded() == []  # ...with the host's pid in the run file by then


async def test_a_real_instance_gets_a_host_of_its_own(data_dir: Path) -> None:
    # A real backend never shares: its failure to start (no bulb address) touches no simulator.
    world = world_of(
        drivers_for_tests(with_tapo=True),
        data_dir,
        kitchen_light={"driver": "tapo"},
        desk_lamp={"driver": "tapo"},
        broken_bulb={"driver": "tapo", "backend": "real"},
    )
    async with DeviceSupervisor(world, data_dir, TOKEN, **FAST | {"backoff_base": 60}) as supervisor:
        directory = supervisor.directory()
        assert directory["broken_bulb"].status == "failed"
        assert "needs host" in (directory["broken_bulb"].error or "")
        assert directory["kitchen_light"].status == directory["desk_lamp"].status == "healthy"
        assert supervisor.log_file("broken_bulb").is_file()


async def test_a_background_device_does_not_hold_up_start_and_boots_when_released(data_dir: Path) -> None:
    from rosaos_tapo.plugin import SPEC

    slow = SPEC.model_copy(update={"background_start": True})  # as the Reachy simulator declares
    registry = load_drivers(allow={"test_drivers"}, extra_plugins={"test_drivers": plugin(slow)})
    world = world_of(registry, data_dir, slow_lamp={"driver": "tapo"})
    async with DeviceSupervisor(world, data_dir, TOKEN, defer_background=True, **FAST) as supervisor:
        entry = supervisor.directory()["slow_lamp"]
        assert (entry.status, entry.url) == ("starting", None)  # start() returned without it
        await asyncio.sleep(0.5)
        assert supervisor.directory()["slow_lamp"].status == "starting"  # not before the release
        supervisor.release_background()
        await supervisor.settle(["slow_lamp"])
        assert supervisor.directory()["slow_lamp"].status == "healthy"


async def test_a_background_simulator_joins_the_running_shared_host_without_holding_up_the_rest(
    data_dir: Path,
) -> None:
    # As the Reachy simulator: its boot waits for the release, then it is served by the same
    # process as the other simulators (no interpreter of its own), on its own URL.
    from rosaos_spotify.plugin import SPEC as SPOTIFY
    from rosaos_tapo.plugin import SPEC as TAPO

    slow = SPOTIFY.model_copy(update={"background_start": True})
    registry = load_drivers(allow={"test_drivers"}, extra_plugins={"test_drivers": plugin(TAPO, slow)})
    world = world_of(
        registry,
        data_dir,
        kitchen_light={"driver": "tapo", "sim": {"on": False}},
        music={"driver": "spotify"},
    )
    supervisor = DeviceSupervisor(world, data_dir, TOKEN, defer_background=True, **FAST)
    witness = HealthWitness(supervisor)
    supervisor.on_status_change = witness
    async with supervisor:
        directory = supervisor.directory()
        assert (directory["kitchen_light"].status, directory["music"].status) == ("healthy", "starting")
        await asyncio.sleep(0.5)
        assert supervisor.directory()["music"].status == "starting"  # not before the release
        supervisor.release_background()
        await supervisor.settle(["music"])
        directory = supervisor.directory()
        assert {e.status for e in directory.values()} == {"healthy"}
        served = pids(data_dir)
        assert served["kitchen_light"] == served["music"] != os.getpid()
        assert directory["kitchen_light"].url != directory["music"].url
        music = DeviceClient(directory["music"].url or "", TOKEN, 5.0, "music")
        assert (await music.get_state())["is_playing"] is False  # its own backend, served
        # A crash of the shared host brings the joined instance back too, again in one process.
        os.kill(served["music"] or 0, signal.SIGKILL)
        await eventually(
            lambda: all(e.status == "healthy" and e.restarts == 1 for e in supervisor.directory().values())
        )
        again = pids(data_dir)
        assert again["kitchen_light"] == again["music"] not in (None, served["music"])
    assert ("music", "healthy", "restarting") in witness.changes
    assert {name for name, _, _ in witness.healthy} == {"kitchen_light", "music"}
    assert witness.reported_before_recorded() == []  # the joined one too, each time
