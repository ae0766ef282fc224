"""The simulated daemon loads its MuJoCo scene pre-compiled: the same model, 160 MiB lighter.

``rosaos_reachy.sim_daemon`` compiles the SDK's scene once in a child process and serves the
daemon's ``MjModel.from_xml_path`` from the ``.mjb``; these tests hold that the model is the
same one, that a changed scene is compiled anew, and that the daemon runs either way.
"""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from rosaos_reachy import sim_daemon
from rosaos_reachy.daemon import SimDaemon, daemon_command

BOX = (
    '<mujoco><worldbody><body><freejoint/><geom type="box" size="{size} .1 .1"/></body></worldbody></mujoco>'
)


def tiny_scene(root: Path, size: float = 0.1) -> Path:
    """A scene laid out as the SDK's is (``mjcf/scenes/<name>.xml``), small enough to compile at once."""
    xml = root / "mjcf" / "scenes" / "empty.xml"
    xml.parent.mkdir(parents=True, exist_ok=True)
    xml.write_text(BOX.format(size=size))
    return xml


def arrays(model: mujoco.MjModel) -> dict[str, np.ndarray]:
    found = {}
    for name in dir(model):
        value = getattr(model, name) if not name.startswith("_") else None
        if isinstance(value, np.ndarray):
            found[name] = value
    return found


def test_the_compiled_reachy_scene_is_the_xml_scene_bit_for_bit(tmp_path: Path) -> None:
    xml = sim_daemon.scene_xml()
    compiled = sim_daemon.compiled_scene(xml, tmp_path)
    from_xml = mujoco.MjModel.from_xml_path(str(xml))
    from_mjb = mujoco.MjModel.from_binary_path(str(compiled))
    expected, loaded = arrays(from_xml), arrays(from_mjb)
    assert expected.keys() == loaded.keys() and len(expected) > 100
    different = [
        name for name in expected if not np.array_equal(expected[name], loaded[name], equal_nan=True)
    ]
    assert different == []
    # And the physics runs the same, step for step, under the same commands.
    runs = [mujoco.MjData(from_xml), mujoco.MjData(from_mjb)]
    commands = np.random.default_rng(7).uniform(-0.5, 0.5, (300, from_xml.nu))
    for command in commands:
        for model, data in zip((from_xml, from_mjb), runs, strict=True):
            data.ctrl[:] = command
            mujoco.mj_step(model, data)
    assert np.array_equal(runs[0].qpos, runs[1].qpos) and np.abs(runs[0].qpos).max() > 0.01


def test_a_changed_scene_is_compiled_anew_and_the_stale_model_removed(tmp_path: Path) -> None:
    xml = tiny_scene(tmp_path / "sdk")
    first = sim_daemon.compiled_scene(xml, tmp_path / "cache")
    assert sim_daemon.compiled_scene(xml, tmp_path / "cache") == first  # kept between starts
    xml.write_text(BOX.format(size=0.3))
    second = sim_daemon.compiled_scene(xml, tmp_path / "cache")
    assert second != first and not first.exists()
    assert mujoco.MjModel.from_binary_path(str(second)).geom_size[0][0] == pytest.approx(0.3)


def test_a_scene_that_does_not_compile_says_why(tmp_path: Path) -> None:
    xml = tiny_scene(tmp_path / "sdk")
    xml.write_text("<mujoco><worldbody><geom type='box'/>")
    with pytest.raises(RuntimeError, match=r"compiling .*empty\.xml failed"):
        sim_daemon.compiled_scene(xml, tmp_path / "cache")


def test_only_the_scene_is_served_compiled(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(mujoco.MjModel, "from_xml_path", mujoco.MjModel.__dict__["from_xml_path"])
    scene = tiny_scene(tmp_path / "sdk")
    other = tiny_scene(tmp_path / "other", size=0.2)
    compiled = sim_daemon.compiled_scene(scene, tmp_path / "cache")
    scene.write_text(BOX.format(size=0.4))  # the served model is the compiled one, not this
    sim_daemon.serve_compiled(scene, compiled)
    assert mujoco.MjModel.from_xml_path(str(scene)).geom_size[0][0] == pytest.approx(0.1)
    assert mujoco.MjModel.from_xml_path(str(other)).geom_size[0][0] == pytest.approx(0.2)


def test_only_mujoco_runs_through_the_launcher(tmp_path: Path) -> None:
    command = daemon_command("mujoco", 8123, tmp_path)
    assert command[1:3] == ["-m", "rosaos_reachy.sim_daemon"]
    assert command[command.index("--model-cache") + 1] == str(tmp_path)
    assert command[command.index("--scene") + 1] == sim_daemon.SCENE
    assert "rosaos_reachy.sim_daemon" not in daemon_command("mockup", 8123, tmp_path)


@pytest.mark.slow
async def test_the_daemon_runs_on_the_compiled_scene(tmp_path: Path) -> None:
    daemon = await SimDaemon.start("mujoco", tmp_path, 120, model_cache=tmp_path / "models")
    try:
        assert daemon.mode == "mujoco" and daemon.process.poll() is None
        assert "loaded the compiled scene" in daemon.log_file.read_text()
    finally:
        await daemon.stop()


@pytest.mark.slow
async def test_the_daemon_still_runs_when_the_scene_cannot_be_cached(tmp_path: Path) -> None:
    not_a_directory = tmp_path / "models"
    not_a_directory.write_text("a file where the cache should be")
    daemon = await SimDaemon.start("mujoco", tmp_path / "logs", 120, model_cache=not_a_directory)
    try:
        assert daemon.mode == "mujoco" and daemon.process.poll() is None
        assert "the daemon compiles its scene itself" in daemon.log_file.read_text()
    finally:
        await daemon.stop()
