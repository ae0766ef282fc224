"""Every driver package under plugins/ runs the conformance kit against each driver it declares.

The kit itself runs as part of the root suite, through each plugin's own tests (``testpaths``
includes ``plugins``); this meta-test makes sure no plugin can leave it out.
"""

from __future__ import annotations

import ast
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PLUGINS = sorted(path.parent for path in (REPO / "plugins").glob("*/pyproject.toml"))
KIT = "DriverConformance"


def declared_drivers(package: Path) -> set[str]:
    """Entry point names in the package's ``rosaos.drivers`` group (the driver names)."""
    project = tomllib.loads((package / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    return set(project.get("entry-points", {}).get("rosaos.drivers", {}))


def conformance_classes(package: Path) -> dict[str, str | None]:
    """Test classes subclassing ``DriverConformance`` in ``tests/``: class name → its ``driver``."""
    found: dict[str, str | None] = {}
    for path in sorted((package / "tests").rglob("test_*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
            if isinstance(node, ast.ClassDef) and any(_names_kit(base) for base in node.bases):
                found[node.name] = _driver_attribute(node)
    return found


def _names_kit(base: ast.expr) -> bool:
    return (isinstance(base, ast.Name) and base.id == KIT) or (
        isinstance(base, ast.Attribute) and base.attr == KIT
    )


def _driver_attribute(node: ast.ClassDef) -> str | None:
    for statement in node.body:
        targets = (
            statement.targets
            if isinstance(statement, ast.Assign)
            else [statement.target]
            if isinstance(statement, ast.AnnAssign)
            else []
        )
        value = getattr(statement, "value", None)
        if any(isinstance(t, ast.Name) and t.id == "driver" for t in targets) and isinstance(
            value, ast.Constant
        ):
            return str(value.value)
    return None


def test_the_built_in_plugins_are_all_found() -> None:
    assert {package.name for package in PLUGINS} >= {
        "rosaos-tapo",
        "rosaos-ros",
        "rosaos-reachy",
        "rosaos-spotify",
    }


@pytest.mark.parametrize("package", PLUGINS, ids=[package.name for package in PLUGINS])
def test_every_declared_driver_has_a_conformance_class(package: Path) -> None:
    drivers = declared_drivers(package)
    assert drivers, f'{package.name}: no [project.entry-points."rosaos.drivers"] in pyproject.toml'
    classes = conformance_classes(package)
    covered = {driver for driver in classes.values() if driver}
    missing = sorted(drivers - covered)
    assert not missing, (
        f"{package.name}: no test class runs the conformance kit for {', '.join(missing)}; add to "
        f"tests/test_conformance.py:\n\nfrom rosaos.testing import {KIT}\n\n\n"
        f'class Test{missing[0].title().replace("_", "")}Driver({KIT}):\n    driver = "{missing[0]}"\n'
    )


def test_the_scan_recognises_a_conformance_class(tmp_path: Path) -> None:
    package = tmp_path / "rosaos-lamp"
    (package / "tests").mkdir(parents=True)
    (package / "tests" / "test_conformance.py").write_text(
        "import rosaos.testing\n\n"
        "class TestLamp(rosaos.testing.DriverConformance):\n    driver = 'lamp'\n\n"
        "class TestOther:\n    driver = 'other'\n",
        encoding="utf-8",
    )
    assert conformance_classes(package) == {"TestLamp": "lamp"}
