"""The published artefacts work: the ``rosaos`` and ``rosaos-tapo`` wheels, installed with plain pip
into a fresh venv, find each other through the entry point and serve the demo world.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[1]


def find_uv() -> str:
    """uv from the repo's venv (scripts/bootstrap.sh installs it there), else from PATH."""
    local = REPO / ".venv" / "bin" / "uv"
    found = str(local) if local.is_file() else shutil.which("uv")
    if found is None:
        pytest.fail("uv not found: run scripts/bootstrap.sh, or pip install uv")
    return found


def run(command: list[str], cwd: Path | None = None, **env: str) -> subprocess.CompletedProcess[str]:
    """Run ``command`` without the dev venv or any ROSAOS_* setting leaking in; fail with its output."""
    child_env = {
        key: value
        for key, value in os.environ.items()
        if key not in {"VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME"} and not key.startswith("ROSAOS_")
    }
    result = subprocess.run(
        command, cwd=cwd, env=child_env | env, capture_output=True, text=True, timeout=600, check=False
    )
    assert result.returncode == 0, f"{' '.join(command)} failed:\n{result.stdout}\n{result.stderr}"
    return result


@pytest.fixture(scope="module")
def wheels(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The rosaos and rosaos-tapo wheels, built from this checkout."""
    dist = tmp_path_factory.mktemp("dist")
    for project in (REPO / "rosaos-core", REPO / "plugins" / "rosaos-tapo"):
        run([find_uv(), "build", "--wheel", "--quiet", "--out-dir", str(dist), str(project)])
    built = {path.name.split("-")[0]: path for path in dist.glob("*.whl")}
    assert set(built) == {"rosaos", "rosaos_tapo"}, sorted(dist.iterdir())
    return built


@pytest.fixture(scope="module")
def venv(tmp_path_factory: pytest.TempPathFactory, wheels: dict[str, Path]) -> Path:
    """A fresh venv with the two wheels installed by plain pip, pinned by constraints.txt.

    The pip is the dev venv's (``pip==`` in constraints.txt), pointed at the new venv with
    ``--python``: the one ``venv`` bundles is years older, and its resolver took most of this
    module's minute. ``--no-compile``: bytecode is written on first import instead, and nothing
    here is about it."""
    venv = tmp_path_factory.mktemp("wheels-venv") / "venv"
    run([sys.executable, "-m", "venv", "--without-pip", str(venv)])
    pip = [sys.executable, "-m", "pip", "--python", str(venv / "bin" / "python"), "install"]
    run(
        [
            *pip,
            "--quiet",
            "--disable-pip-version-check",
            "--no-compile",
            "--constraint",
            str(REPO / "constraints.txt"),
            str(wheels["rosaos"]),
            str(wheels["rosaos_tapo"]),
        ]
    )
    return venv


def test_the_rosaos_wheel_ships_the_driver_template(wheels: dict[str, Path]) -> None:
    names = set(zipfile.ZipFile(wheels["rosaos"]).namelist())
    template = "rosaos/_templates/driver/"
    assert f"{template}copier.yml" in names
    assert f"{template}template/src/{{{{ module }}}}/plugin.py.jinja" in names


def test_the_tapo_wheel_ships_its_prompt_and_intents(wheels: dict[str, Path]) -> None:
    names = set(zipfile.ZipFile(wheels["rosaos_tapo"]).namelist())
    assert {"rosaos_tapo/prompt.md", "rosaos_tapo/intents.yaml"} <= names


def test_devices_list_shows_a_healthy_kitchen_light(venv: Path, tmp_path: Path) -> None:
    result = run(
        [str(venv / "bin" / "rosaos"), "devices", "list", "--json"],
        cwd=tmp_path,  # no rosaos.toml here: the demo world
        ROSAOS_DATA_DIR=str(tmp_path / "data"),
        XDG_CONFIG_HOME=str(tmp_path / "config"),
    )
    rows = {row["instance"]: row for row in json.loads(result.stdout)}
    light = rows["kitchen_light"]
    assert (light["driver"], light["package"], light["backend"]) == ("tapo", "rosaos-tapo", "sim")
    assert light["health"].startswith("healthy"), light
    assert light["state"]["on"] is False


def test_new_driver_renders_from_the_installed_wheel(venv: Path, tmp_path: Path) -> None:
    run(
        [
            str(venv / "bin" / "rosaos"),
            "new-driver",
            "--name",
            "wheel_check",
            "--defaults",
            "--dest",
            str(tmp_path),
        ]
    )
    assert (tmp_path / "rosaos-wheel_check" / "src" / "rosaos_wheel_check" / "plugin.py").is_file()
