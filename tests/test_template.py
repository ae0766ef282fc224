"""The driver template works out of the box: ``rosaos new-driver`` renders a package that installs
alone (with rosaos[testing]) into a fresh venv and passes its own tests, the conformance kit included.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[1]
NAME = "acme_plug"
NEW_DRIVER = [sys.executable, "-m", "rosaos.cli", "new-driver"]
PACKAGE_FILES = [
    "pyproject.toml",
    "README.md",
    "src/rosaos_acme_plug/__init__.py",
    "src/rosaos_acme_plug/plugin.py",
    "src/rosaos_acme_plug/server.py",
    "src/rosaos_acme_plug/backend.py",
    "src/rosaos_acme_plug/prompt.md",
    "src/rosaos_acme_plug/intents.yaml",
    "tests/test_conformance.py",
    "tests/test_intents.py",
]


def find_uv() -> str:
    """uv from the repo's venv (scripts/bootstrap.sh installs it there), else from PATH."""
    local = REPO / ".venv" / "bin" / "uv"
    found = str(local) if local.is_file() else shutil.which("uv")
    if found is None:
        pytest.fail("uv not found: run scripts/bootstrap.sh, or pip install uv")
    return found


def clean_env(**extra: str) -> dict[str, str]:
    """This process's environment without what would point a child at the dev venv or config."""
    env = {
        key: value
        for key, value in os.environ.items()
        if key not in {"VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME"} and not key.startswith("ROSAOS_")
    }
    return env | extra


def run(command: list[str], cwd: Path | None = None, **env: str) -> subprocess.CompletedProcess[str]:
    result = subprocess.run(
        command, cwd=cwd, env=clean_env(**env), capture_output=True, text=True, timeout=600, check=False
    )
    assert result.returncode == 0, f"{' '.join(command)} failed:\n{result.stdout}\n{result.stderr}"
    return result


@pytest.fixture(scope="module")
def rendered(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The package ``rosaos new-driver --name acme_plug --concurrency shared --defaults`` writes."""
    dest = tmp_path_factory.mktemp("drivers")
    run([*NEW_DRIVER, "--name", NAME, "--concurrency", "shared", "--defaults", "--dest", str(dest)])
    return dest / f"rosaos-{NAME}"


@pytest.fixture(scope="module")
def venv(tmp_path_factory: pytest.TempPathFactory, rendered: Path) -> Path:
    """A fresh venv with only the local rosaos[testing] and the rendered package (not editable)."""
    uv = find_uv()
    venv = tmp_path_factory.mktemp("template-venv") / "venv"
    run([uv, "venv", "--quiet", "--python", sys.executable, str(venv)])
    install = [uv, "pip", "install", "--quiet", "--python", str(venv / "bin" / "python")]
    run([*install, "-c", str(REPO / "constraints.txt"), f"{REPO / 'rosaos-core'}[testing]", str(rendered)])
    return venv


def test_the_package_has_the_shape_of_the_built_in_drivers(rendered: Path) -> None:
    missing = [name for name in PACKAGE_FILES if not (rendered / name).is_file()]
    assert not missing, f"missing from the rendered package: {missing}"


def test_the_answers_reach_the_package(rendered: Path) -> None:
    plugin = (rendered / "src" / "rosaos_acme_plug" / "plugin.py").read_text(encoding="utf-8")
    pyproject = (rendered / "pyproject.toml").read_text(encoding="utf-8")
    assert 'concurrency="shared"' in plugin
    assert 'acme_plug = "rosaos_acme_plug.plugin"' in pyproject


@pytest.mark.parametrize("name", ["acme_plug", "zebra_fan"])  # names sort before and after rosaos
def test_the_rendered_code_passes_the_repo_lint_rules(name: str, tmp_path: Path) -> None:
    run([*NEW_DRIVER, "--name", name, "--defaults", "--dest", str(tmp_path)])
    ruff = [sys.executable, "-m", "ruff"]
    first_party = f"lint.isort.known-first-party=['rosaos', 'rosaos_{name}']"
    config = ["--no-cache", "--config", str(REPO / "pyproject.toml"), "--config", first_party]
    run([*ruff, "check", *config, str(tmp_path)])
    run([*ruff, "format", "--check", *config, str(tmp_path)])


def test_the_rendered_tests_pass_in_a_fresh_venv(venv: Path, rendered: Path, tmp_path: Path) -> None:
    result = run(
        [str(venv / "bin" / "python"), "-m", "pytest", "-q", "-p", "no:cacheprovider", "tests"],
        cwd=rendered,
        HOME=str(tmp_path),
        XDG_CONFIG_HOME=str(tmp_path / "config"),
        XDG_DATA_HOME=str(tmp_path / "data"),
    )
    summary = result.stdout.strip().splitlines()[-1]
    # 24 kit checks (the card's controls and odd numbers among them), the behaviour test and 6
    # intents tests (4 templates, 2 capabilities); nothing skipped: the template covers every check
    # (its card and its notices included).
    assert summary.startswith("31 passed"), result.stdout


def test_the_driver_is_in_the_demo_world_of_the_fresh_venv(venv: Path, tmp_path: Path) -> None:
    result = run(
        [str(venv / "bin" / "rosaos"), "devices", "list", "--json"],
        cwd=tmp_path,
        ROSAOS_DATA_DIR=str(tmp_path / "data"),
        XDG_CONFIG_HOME=str(tmp_path / "config"),
    )
    rows = {row["instance"]: row for row in json.loads(result.stdout)}
    assert list(rows) == ["acme_plug"]  # only rosaos and this driver are installed there
    assert rows["acme_plug"]["health"].startswith("healthy"), rows["acme_plug"]
    assert rows["acme_plug"]["state"] == {"on": False, "level": 50}


CARD_PROBE = """
import asyncio, json
from rosaos.plugins import load_drivers
spec = load_drivers().drivers["acme_plug"].spec
from rosaos_acme_plug.plugin import sim_backend
from rosaos.drivers import DeviceContext
backend = spec.backends["sim"](DeviceContext("acme_plug", "", spec.settings(), "sim", {"on": True, "level": 70}))
state = asyncio.run(backend.state()).model_dump()
print(json.dumps({"card": spec.card.view() if spec.card else None, "state": state}))
"""


def test_the_generated_driver_gets_a_card_from_its_declaration(venv: Path, tmp_path: Path) -> None:
    """A third-party driver declares its card in its own plugin; the kernel hands it to the page.

    The view printed here is what ``GET /devices`` carries under ``card``; the page draws each
    widget kind (rosaos-core/tests/kernel/test_web_cards.py checks the drawing in Chromium).
    """
    result = run([str(venv / "bin" / "python"), "-c", CARD_PROBE], cwd=tmp_path)
    probe = json.loads(result.stdout)
    widgets = probe["card"]["widgets"]
    assert [(w["kind"], w["key"]) for w in widgets] == [("flag", "on"), ("gauge", "level")]
    assert widgets[1]["unit"] == "%"
    assert all(w["key"] in probe["state"] for w in widgets)  # what the conformance kit also checks
