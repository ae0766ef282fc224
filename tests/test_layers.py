"""The layout of ``rosaos``: the command line and the front ends sit on top, nothing below
them imports them, and no two modules share a file name.

The kernel, the device hosting layer, the processes, the models and the offline engine run
without a terminal (in the kernel, in workers, in device hosts). If one of them imported
``rosaos.cli`` or ``rosaos.frontends``, the layout would lie about the architecture and a worker
would load typer and rich for nothing. Imports inside functions count too: a lazy import is
still a dependency.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "rosaos-core" / "src" / "rosaos"
LOWER_LAYERS = ["kernel", "devices", "processes", "models", "intents", "drivers.py"]
UPPER_LAYERS = ("rosaos.cli", "rosaos.frontends")


def imported_modules(path: Path) -> set[str]:
    """Every module ``path`` imports, at the top or inside a function (absolute names)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            # ``from rosaos import cli`` names the upper layer as an attribute.
            found.update(f"{node.module}.{alias.name}" for alias in node.names)
    return found


def upward(modules: set[str]) -> list[str]:
    """The upper-layer modules among ``modules``."""
    return sorted(
        name for name in modules if any(name == up or name.startswith(f"{up}.") for up in UPPER_LAYERS)
    )


def lower_layer_files() -> list[Path]:
    files: list[Path] = []
    for layer in LOWER_LAYERS:
        target = PACKAGE / layer
        files.extend(sorted(target.rglob("*.py")) if target.is_dir() else [target])
    return files


def test_the_scan_sees_every_lower_layer() -> None:
    files = lower_layer_files()
    for layer in LOWER_LAYERS:
        assert any(path == PACKAGE / layer or PACKAGE / layer in path.parents for path in files), layer
    assert PACKAGE / "kernel" / "loop.py" in files


def test_the_scan_finds_an_upward_import(tmp_path: Path) -> None:
    module = tmp_path / "offender.py"
    module.write_text(
        "from rosaos import cli\n\ndef later() -> None:\n    from rosaos.frontends.chat import chat_command\n"
    )
    found = upward(imported_modules(module))
    assert "rosaos.cli" in found and "rosaos.frontends.chat" in found
    assert upward({"rosaos.kernel.loop", "rosaos.client", "rosaos.frontend"}) == []


def test_lower_layers_do_not_import_the_cli_or_the_front_ends() -> None:
    offenders = {
        str(path.relative_to(PACKAGE)): found
        for path in lower_layer_files()
        if (found := upward(imported_modules(path)))
    }
    assert not offenders, f"lower layers importing rosaos.cli / rosaos.frontends: {offenders}"


def test_core_module_names_are_unique() -> None:
    """Two ``runtime.py`` (or ``world.py``, ``sources.py``) in one package make a reader open both
    to learn which is which; a file's name should say what it does (see the glossary in
    ``docs/architecture.md``)."""
    by_name: dict[str, list[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name not in {"__init__.py", "__main__.py"}:
            by_name.setdefault(path.name, []).append(str(path.relative_to(PACKAGE)))
    assert len(by_name) > 100, "the scan found too few modules"
    clashes = {name: paths for name, paths in by_name.items() if len(paths) > 1}
    assert not clashes, f"core modules sharing a file name (rename one after what it does): {clashes}"
