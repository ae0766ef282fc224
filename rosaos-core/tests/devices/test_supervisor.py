"""DeviceSupervisor: one host process per local instance, health checks, restarts, the run file."""

from __future__ import annotations

import json
import os
import signal
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
import pytest_asyncio

from rosaos.devices.client import DeviceClient
from rosaos.devices.run_files import run_file_path, served_devices
from rosaos.devices.supervisor import DeviceSupervisor
from rosaos.devices.world import World
from rosaos.drivers import DeviceError

from .devices_support import (
    HealthWitness,
    closed_port_url,
    drivers_for_tests,
    eventually,
    pid_alive,
    requires_tapo,
    tapo_installed,
    world_of,
)

# One event loop for the module, so one supervisor can serve every test that only looks.
pytestmark = [pytest.mark.slow, pytest.mark.asyncio(loop_scope="module")]

TOKEN = "supervisor-test-token"
FAST: dict[str, Any] = {"health_interval": 0.2, "health_timeout": 2.0, "backoff_base": 0.1, "stop_grace": 2.0}


def tapo_world(data_dir: Path, **extra: dict[str, Any]) -> World:
    devices = {"kitchen_light": {"driver": "tapo", "sim": {"on": False}}} | extra
    return world_of(drivers_for_tests(with_tapo=True), data_dir, **devices)


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def shared(tmp_path_factory: pytest.TempPathFactory) -> AsyncIterator[DeviceSupervisor]:
    """One running supervisor for the module: tests that kill its host also wait for the recovery."""
    if not tapo_installed():
        pytest.skip("needs the rosaos-tapo driver installed")
    data_dir = tmp_path_factory.mktemp("shared") / "data"
    supervisor = DeviceSupervisor(tapo_world(data_dir), data_dir, TOKEN, **FAST)
    supervisor.on_status_change = HealthWitness(supervisor)
    async with supervisor as running:
        yield running


def runtime(data_dir: Path) -> dict[str, Any]:
    devices = json.loads(run_file_path(data_dir).read_text())["devices"]
    assert isinstance(devices, dict)
    return devices


async def test_a_local_instance_is_served_in_its_own_healthy_process(shared: DeviceSupervisor) -> None:
    entry = shared.directory()["kitchen_light"]
    assert entry.status == "healthy"
    assert entry.url is not None
    assert entry.token == TOKEN
    assert await DeviceClient(entry.url, TOKEN).get_state() == {
        "on": False,
        "brightness": 100,
        "hue": 0,
        "saturation": 0,
        "color_temp": 2700,
    }
    assert runtime(shared.data_dir)["kitchen_light"]["pid"] not in (None, os.getpid())


async def test_the_runtime_file_lists_served_instances_for_other_commands(shared: DeviceSupervisor) -> None:
    entry = runtime(shared.data_dir)["kitchen_light"]
    assert entry["url"] == shared.directory()["kitchen_light"].url
    assert entry["status"] == "healthy"
    assert entry["since"]
    assert served_devices(shared.data_dir)["kitchen_light"].url == entry["url"]


async def test_safe_stop_reaches_every_served_instance(shared: DeviceSupervisor) -> None:
    outcomes = await shared.safe_stop_all()
    assert [(o.instance, o.ok) for o in outcomes] == [("kitchen_light", True)]


async def test_a_second_supervisor_on_the_same_data_dir_is_refused(data_dir: Path) -> None:
    # A run file left by a live supervisor (here: our parent process stands in for it).
    path = run_file_path(data_dir)
    path.parent.mkdir(parents=True)
    path.write_text(json.dumps({"supervisor_pid": os.getppid(), "devices": {}}))
    world = world_of(drivers_for_tests(), data_dir, lamp={"driver": "tiny"})
    with pytest.raises(DeviceError, match="already served by another rosaOS"):
        async with DeviceSupervisor(world, data_dir, TOKEN):
            pass
    assert path.exists(), "the other supervisor's run file must be left alone"


@requires_tapo
async def test_stop_terminates_the_hosts_and_removes_the_runtime_file(data_dir: Path) -> None:
    async with DeviceSupervisor(tapo_world(data_dir), data_dir, TOKEN, **FAST) as supervisor:
        pid = runtime(data_dir)["kitchen_light"]["pid"]
        assert pid_alive(pid)
    assert not pid_alive(pid)
    assert not run_file_path(data_dir).exists()
    assert supervisor.directory()["kitchen_light"].status == "stopped"


async def restarted_and_healthy(supervisor: DeviceSupervisor, restarts_before: int) -> None:
    def done() -> bool:
        entry = supervisor.directory()["kitchen_light"]
        return entry.restarts == restarts_before + 1 and entry.status == "healthy"

    await eventually(done)


async def test_a_killed_host_is_restarted_at_the_same_url(shared: DeviceSupervisor) -> None:
    before = shared.directory()["kitchen_light"]
    old_pid = runtime(shared.data_dir)["kitchen_light"]["pid"]
    os.kill(old_pid, signal.SIGKILL)
    await restarted_and_healthy(shared, before.restarts)
    assert shared.directory()["kitchen_light"].url == before.url
    assert runtime(shared.data_dir)["kitchen_light"]["pid"] not in (None, old_pid)
    # Its pid was in the run file when it was called healthy, at the first start and now.
    witness = shared.on_status_change
    assert isinstance(witness, HealthWitness)
    assert [name for name, _, _ in witness.healthy].count("kitchen_light") >= 2
    assert witness.reported_before_recorded() == []
    assert before.url is not None
    assert (await DeviceClient(before.url, TOKEN).get_state())["on"] is False


@requires_tapo
async def test_a_host_that_cannot_start_is_reported_and_not_fatal(data_dir: Path) -> None:
    # The real backend without a bulb address: the driver's own fix-it message must come through.
    world = world_of(
        drivers_for_tests(with_tapo=True), data_dir, broken_bulb={"driver": "tapo", "backend": "real"}
    )
    # A long backoff: one attempt is enough to see the report, and retries would only burn CPU.
    async with DeviceSupervisor(world, data_dir, TOKEN, **FAST | {"backoff_base": 60}) as supervisor:
        broken = supervisor.directory()["broken_bulb"]
        assert broken.status == "failed"
        assert broken.url is None
        assert broken.error is not None
        assert "needs host" in broken.error
        assert runtime(data_dir)["broken_bulb"]["error"] == broken.error


async def test_placeholders_are_listed_not_served_and_remote_ones_only_probed(data_dir: Path) -> None:
    world = world_of(
        drivers_for_tests(),
        data_dir,
        robot={"driver": "someday"},
        far_lamp={"driver": "tiny", "url": closed_port_url()},
    )
    async with DeviceSupervisor(world, data_dir, TOKEN, **FAST) as supervisor:
        directory = supervisor.directory()
        assert directory["robot"].status == "not implemented"
        assert directory["robot"].url is None
        assert directory["far_lamp"].status == "unreachable"
        assert directory["far_lamp"].remote
        assert directory["far_lamp"].error is not None
        assert "nothing is listening" in directory["far_lamp"].error
        outcomes = {o.instance: o for o in await supervisor.safe_stop_all(per_device_timeout=1)}
        assert not outcomes["far_lamp"].ok
        assert (outcomes["robot"].ok, outcomes["robot"].detail) == (
            True,
            "not served (not implemented): nothing to stop",
        )
