"""A task file's world on simulators: resolved against the installed drivers, served in-process."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from types import ModuleType

from fastmcp import FastMCP

from rosaos import hookimpl
from rosaos.bench.results import TrialResult
from rosaos.bench.runner import run_file
from rosaos.bench.sim_world import SimDevices, bench_world
from rosaos.bench.tasks import TaskSelection, load_task_file
from rosaos.config import RosaosConfig
from rosaos.devices.client import DeviceClient
from rosaos.drivers import DeviceBackend, DeviceError, DriverSpec
from rosaos.plugins import load_drivers

REGISTRY = load_drivers()


@hookimpl
def _register_arm(register: Callable[[DriverSpec], None]) -> None:
    """A placeholder driver, as a driver package registers one before it is written."""
    register(
        DriverSpec(
            name="arm",
            title="Robot arm",
            description="A robot arm (placeholder).",
            concurrency="exclusive",
            prompt="You control the arm.",
            server=lambda ctx, backend: FastMCP(ctx.instance),
            backends={"sim": lambda ctx: DeviceBackend()},
            implemented=False,
        )
    )


_arm = ModuleType("arm_plugin")
_arm.register_drivers = _register_arm  # type: ignore[attr-defined]
WITH_PLACEHOLDER = load_drivers(extra_plugins={"arm": _arm})


class Recorder:
    """A ``BenchProgress`` that remembers what it was told."""

    def __init__(self) -> None:
        self.finished_ids: list[str] = []

    def started(self, task_id: str, trial: int) -> None:
        pass

    def finished(self, task_id: str, result: TrialResult | None) -> None:
        self.finished_ids.append(task_id)


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def desk(tmp_path: Path, extra: str = "") -> Path:
    path = tmp_path / "desk.yaml"
    path.write_text(
        "name: desk\n"
        "world:\n"
        "  lamp:\n"
        "    driver: tapo\n"
        "    state: {on: false, brightness: 100}\n"
        "    sim: {timeout: 7}\n"
        + extra
        + "tasks:\n  - {id: t1, say: Lamp on, expect: {lamp: {on: true}}}\n",
        encoding="utf-8",
    )
    return path


def test_a_sim_key_the_driver_settings_declare_becomes_a_setting(tmp_path: Path) -> None:
    # As the README's ros `sim: {profile: turtlebot4}`: here Tapo's `timeout` setting.
    world = bench_world(load_task_file(desk(tmp_path)), REGISTRY)
    lamp = world.world.get("lamp")
    assert lamp.settings.model_dump()["timeout"] == 7
    assert "timeout" not in lamp.sim
    assert lamp.sim == {"on": False, "brightness": 100}


def test_a_driver_that_is_not_installed_is_unavailable_with_the_installed_ones(tmp_path: Path) -> None:
    world = bench_world(load_task_file(desk(tmp_path, "  drone:\n    driver: drone\n")), REGISTRY)
    assert "drone" not in world.world.instances
    assert world.unavailable["drone"].startswith("driver 'drone' not installed (installed: ")


def test_a_placeholder_driver_is_listed_but_unavailable(tmp_path: Path) -> None:
    world = bench_world(load_task_file(desk(tmp_path, "  arm:\n    driver: arm\n")), WITH_PLACEHOLDER)
    assert "arm" in world.world.instances
    assert world.unavailable == {"arm": "driver 'arm' not implemented"}


async def test_a_task_that_needs_a_placeholder_driver_is_pending_and_not_run(tmp_path: Path) -> None:
    text = desk(tmp_path, "  arm:\n    driver: arm\n").read_text(encoding="utf-8")
    text = text.replace("expect: {lamp: {on: true}}", "expect: {arm: {x: 1}}")
    task_file = load_task_file(write(tmp_path / "arm.yaml", text))
    progress = Recorder()
    config = RosaosConfig(data_dir=tmp_path / "data")
    result = await run_file(TaskSelection(task_file, task_file.tasks), config, WITH_PLACEHOLDER, 1, progress)
    [task] = result.tasks
    assert task.pending == "arm: driver 'arm' not implemented"
    assert task.trials == []
    assert progress.finished_ids == ["t1"]


async def test_restart_puts_the_simulator_back_in_the_given_state_at_the_same_url(tmp_path: Path) -> None:
    world = bench_world(load_task_file(desk(tmp_path)), REGISTRY)
    devices = SimDevices(world.world, tmp_path / "data")
    await devices.start()
    try:
        url = devices.directory()["lamp"].url
        assert url is not None
        await DeviceClient(url, devices.token, name="lamp").call("turn_on")
        await devices.restart({"lamp": world.simulator_state("lamp", {"on": False, "brightness": 30})})
        states, errors = await devices.read_states()
        assert devices.directory()["lamp"].url == url
    finally:
        await devices.stop()
    assert errors == {}
    assert states["lamp"]["on"] is False
    assert states["lamp"]["brightness"] == 30


async def test_the_simulators_need_the_bearer_token(tmp_path: Path) -> None:
    world = bench_world(load_task_file(desk(tmp_path)), REGISTRY)
    devices = SimDevices(world.world, tmp_path / "data")
    await devices.start()
    try:
        url = devices.directory()["lamp"].url
        assert url is not None
        refused = await _refused(DeviceClient(url, "wrong-token", name="lamp"))
    finally:
        await devices.stop()
    assert refused


async def _refused(client: DeviceClient) -> bool:
    try:
        await client.get_state()
    except DeviceError:
        return True
    return False
