"""``rosaos new-driver``: scaffold a driver package from the copier template.

The template lives at the repository's ``templates/driver/`` and ships inside the wheel as
``rosaos/_templates/driver``, so the command works from a plain ``pip install rosaos`` as well as
from a development checkout. The rendered package has the shape of the built-in drivers and
passes the conformance kit out of the box.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

import typer

from rosaos.drivers import DRIVER_NAME

CONCURRENCY_CHOICES = ("exclusive", "shared")
PLUGINS_DIR = Path("plugins")


class ScaffoldError(Exception):
    """The driver cannot be scaffolded as asked; the message says what to change."""


def template_path() -> Path:
    """The copier template: the copy in the installed wheel, else the repository's (editable install)."""
    here = Path(__file__).resolve().parent
    candidates = [
        here / "_templates" / "driver",  # wheel: hatch force-include puts it here
        here.parents[2] / "templates" / "driver",  # checkout: rosaos-core/src/rosaos/ → repo root
    ]
    for candidate in candidates:
        if (candidate / "copier.yml").is_file():
            return candidate
    raise ScaffoldError(
        "the driver template is missing from this rosaos install "
        f"(looked in {', '.join(str(c) for c in candidates)}); reinstall rosaos"
    )


def check_name(name: str) -> str:
    """Return ``name`` if it is a valid driver name, else raise :class:`ScaffoldError` saying why."""
    if not DRIVER_NAME.match(name):
        raise ScaffoldError(
            f"invalid driver name {name!r}: start with a lowercase letter and use only lowercase "
            "letters, digits and underscores (e.g. acme_plug)"
        )
    return name


def default_dest(dest: Path | None) -> Path:
    """``dest`` if given; else ``./plugins`` when it exists (the rosaOS repo layout), else ``.``."""
    if dest is not None:
        return dest
    if PLUGINS_DIR.is_dir():
        return PLUGINS_DIR
    return Path()


def render_driver(target: Path, data: dict[str, Any], *, defaults: bool) -> None:
    """Render the template into ``target`` (which must not exist) with copier.

    The template is copied to a temporary directory first: copier renders a template that sits at
    the root of a git repository from its latest tag, and the working tree is what we want.
    """
    from copier import run_copy  # copier is slow to import; only this command needs it

    if target.exists():
        raise ScaffoldError(f"{target} already exists; choose another --name or --dest, or remove it")
    with tempfile.TemporaryDirectory(prefix="rosaos-template-") as scratch:
        template = Path(scratch) / "driver"
        shutil.copytree(template_path(), template, ignore=shutil.ignore_patterns("__pycache__", ".git"))
        run_copy(str(template), target, data=data, defaults=defaults, quiet=True, unsafe=False)


def new_driver_command(
    name: str | None,
    title: str | None,
    description: str | None,
    concurrency: str | None,
    author: str | None,
    dest: Path | None,
    defaults: bool,
) -> int:
    """Scaffold ``<dest>/rosaos-<name>/`` and print the next steps. Returns the exit code.

    Flags answer the template's questions; copier asks the rest, or takes their defaults with
    ``--defaults``. The name is asked first (it names the folder) and checked before rendering.
    """
    try:
        interactive = not defaults and sys.stdin.isatty()
        if name is None:
            if not interactive:
                raise ScaffoldError("give the driver name with --name (e.g. --name acme_plug)")
            name = typer.prompt("Driver name (lowercase letters, digits, underscores)")
        check_name(name)
        if concurrency is not None and concurrency not in CONCURRENCY_CHOICES:
            raise ScaffoldError(f"--concurrency must be exclusive or shared, not {concurrency!r}")
        answers = {"title": title, "description": description, "concurrency": concurrency, "author": author}
        if not defaults and not interactive and None in answers.values():
            raise ScaffoldError(
                "no terminal to ask the remaining questions on: pass --defaults or every option"
            )
        data = {"name": name} | {key: value for key, value in answers.items() if value is not None}
        target = default_dest(dest) / f"rosaos-{name}"
        render_driver(target, data, defaults=defaults)
    except ScaffoldError as error:
        typer.echo(f"rosaos new-driver: {error}", err=True)
        return 2
    except (KeyboardInterrupt, EOFError):
        typer.echo("rosaos new-driver: cancelled", err=True)
        return 130
    except Exception as error:  # copier's own errors (validation, rendering) carry a readable message
        typer.echo(f"rosaos new-driver: the template could not be rendered: {error}", err=True)
        return 1
    steps = [
        (f"pip install -e '{target}[test]'", "the driver, and the conformance kit"),
        (f"pytest {target}", "the conformance kit and the behaviour tests"),
        ("rosaos devices list", "the demo world now includes it, on its simulator"),
    ]
    width = max(len(command) for command, _ in steps)
    typer.echo(f"Created {target}/ (driver {name!r}).\n\nNext steps:")
    for command, why in steps:
        typer.echo(f"  {command.ljust(width)}  # {why}")
    typer.echo(f"Then replace the simulated device in {target}/src/rosaos_{name}/backend.py with yours.")
    return 0
