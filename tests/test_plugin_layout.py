"""Every driver has one layout: the built-in ones and what ``rosaos new-driver`` renders.

``plugin.py`` (the DriverSpec), ``settings.py`` (the settings model), ``server.py`` and/or
``tools/*.py`` (each with ``register(mcp, backend)``), ``backend.py``, ``prompt.md`` and
``intents.yaml``. A newcomer who has read one driver knows where everything is in the next.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from rosaos.plugins import load_drivers
from rosaos.scaffold import render_driver

ROOT = Path(__file__).resolve().parent.parent
REQUIRED = ("__init__.py", "plugin.py", "settings.py", "backend.py", "prompt.md", "intents.yaml")
BUILT_IN = sorted(path for path in (ROOT / "plugins").glob("rosaos-*/src/rosaos_*") if path.is_dir())


def layout_problems(package: Path) -> list[str]:
    """What in ``package`` (a driver's import package folder) breaks the layout; empty when none."""
    problems = [f"{name} is missing" for name in REQUIRED if not (package / name).is_file()]
    tools = sorted(p for p in (package / "tools").glob("*.py") if p.name != "__init__.py")
    if not (package / "server.py").is_file() and not tools:
        problems.append("neither server.py nor tools/*.py holds the MCP tools")
    if (package / "server.py").is_file() and "build_server" not in _functions(package / "server.py"):
        problems.append("server.py does not define build_server(ctx, backend)")
    for module in tools:
        register = _functions(module).get("register")
        if register is None or [a.arg for a in register.args.args] != ["mcp", "backend"]:
            problems.append(f"tools/{module.name} does not define register(mcp, backend)")
    for stray in sorted(package.glob("*_tools.py")):
        problems.append(f"{stray.name}: tool modules belong in tools/ (tools/<role>.py with register())")
    settings = package / "settings.py"
    if settings.is_file() and not any(
        isinstance(node, ast.ClassDef) and node.name.endswith("Settings")
        for node in ast.parse(settings.read_text(encoding="utf-8")).body
    ):
        problems.append("settings.py defines no *Settings model")
    return problems


def _functions(module: Path) -> dict[str, ast.FunctionDef | ast.AsyncFunctionDef]:
    tree = ast.parse(module.read_text(encoding="utf-8"))
    return {node.name: node for node in tree.body if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)}


@pytest.mark.parametrize("package", BUILT_IN, ids=[path.name for path in BUILT_IN])
def test_built_in_drivers_have_the_layout(package: Path) -> None:
    assert layout_problems(package) == []


def test_there_are_four_built_in_drivers() -> None:
    assert [path.name for path in BUILT_IN] == [
        "rosaos_reachy",
        "rosaos_ros",
        "rosaos_spotify",
        "rosaos_tapo",
    ]


@pytest.mark.parametrize("package", BUILT_IN, ids=[path.name for path in BUILT_IN])
def test_the_spec_points_at_its_own_files(package: Path) -> None:
    drivers = load_drivers().drivers.values()
    specs = [info.spec for info in drivers if info.spec.server.__module__.split(".")[0] == package.name]
    assert specs, f"no registered driver comes from {package}"
    for spec in specs:
        assert spec.prompt.strip() == (package / "prompt.md").read_text(encoding="utf-8").strip()
        assert spec.intents is not None and Path(spec.intents).resolve() == package / "intents.yaml"
        assert spec.settings.__module__ == f"{package.name}.settings"


def test_the_template_renders_the_layout(tmp_path: Path) -> None:
    target = tmp_path / "rosaos-layout-probe"
    render_driver(target, {"name": "layout_probe"}, defaults=True)
    assert layout_problems(target / "src" / "rosaos_layout_probe") == []


def test_a_stray_tools_module_is_caught(tmp_path: Path) -> None:
    package = tmp_path / "rosaos_bad"
    (package / "tools").mkdir(parents=True)
    for name in REQUIRED:
        (package / name).write_text("", encoding="utf-8")
    (package / "settings.py").write_text("class BadSettings: ...\n", encoding="utf-8")
    (package / "motion_tools.py").write_text("", encoding="utf-8")
    (package / "tools" / "arm.py").write_text("def register(mcp): ...\n", encoding="utf-8")
    assert layout_problems(package) == [
        "tools/arm.py does not define register(mcp, backend)",
        "motion_tools.py: tool modules belong in tools/ (tools/<role>.py with register())",
    ]
