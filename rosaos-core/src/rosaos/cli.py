"""``rosaos ...``: the command line. Each command lives with the role it belongs to; this file wires them.

Commands import their modules lazily so ``rosaos --help`` stays fast.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from rosaos import __version__

app = typer.Typer(
    name="rosaos",
    help="rosaOS: an agentic operating system for embodied LLMs.",
    no_args_is_help=True,
    rich_markup_mode="rich",
    pretty_exceptions_enable=False,
)
devices_app = typer.Typer(help="Inspect and check the device instances of the world.", no_args_is_help=True)
app.add_typer(devices_app, name="devices")

ConfigOption = Annotated[
    Path | None,
    typer.Option(
        "--config",
        "-c",
        help="rosaos.toml to use (default: $ROSAOS_CONFIG, ./rosaos.toml, then the user config dir).",
        exists=False,
        dir_okay=False,
    ),
]
JsonOption = Annotated[bool, typer.Option("--json", help="Print machine-readable JSON.")]


def _version(value: bool) -> None:
    if value:
        typer.echo(f"rosaos {__version__}")
        raise typer.Exit()


@app.callback()
def root(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Print the version and exit.")
    ] = False,
) -> None:
    """rosaOS: an agentic operating system for embodied LLMs."""


@devices_app.command("list")
def devices_list(
    config: ConfigOption = None,
    json_output: JsonOption = False,
    check: Annotated[
        bool, typer.Option("--check/--no-check", help="Health-check each instance (get_state).")
    ] = True,
) -> None:
    """List the device instances: driver, package, concurrency, backend, URL and health."""
    from rosaos.devices.commands import list_devices

    raise typer.Exit(list_devices(config, json_output=json_output, check=check))


@devices_app.command("check")
def devices_check(
    name: Annotated[str, typer.Argument(help="Instance name, e.g. kitchen_light.")],
    config: ConfigOption = None,
    json_output: JsonOption = False,
    timeout: Annotated[float, typer.Option(help="Seconds to wait for the device.")] = 10.0,
) -> None:
    """Connect to one instance, call get_state and print it. Non-zero exit with the reason if it fails."""
    from rosaos.devices.commands import check_device

    raise typer.Exit(check_device(name, config, json_output=json_output, timeout=timeout))


@app.command("serve-device")
def serve_device(
    name: Annotated[str, typer.Argument(help="Instance name from the config (or the demo world).")],
    config: ConfigOption = None,
    host: Annotated[str, typer.Option(help="Address to bind. Loopback unless you mean it.")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="TCP port (0 picks a free one).", min=0, max=65535)] = 0,
) -> None:
    """Serve one instance's MCP server over streamable HTTP, behind the bearer token."""
    from rosaos.devices.commands import serve_device_command

    raise typer.Exit(serve_device_command(name, config, host=host, port=port))


@app.command("new-driver")
def new_driver(
    name: Annotated[str | None, typer.Option(help="Driver name: lowercase, digits, underscores.")] = None,
    title: Annotated[str | None, typer.Option(help="Human title, e.g. 'Acme smart plug'.")] = None,
    description: Annotated[
        str | None, typer.Option(help="What the device does (the kernel reads it).")
    ] = None,
    concurrency: Annotated[str | None, typer.Option(help="exclusive or shared.")] = None,
    author: Annotated[str | None, typer.Option(help="Author name for the package metadata.")] = None,
    dest: Annotated[
        Path | None,
        typer.Option(help="Where to write rosaos-<name>/ (default: ./plugins if it exists, else .)."),
    ] = None,
    defaults: Annotated[
        bool, typer.Option("--defaults", help="Use defaults for every unanswered question.")
    ] = False,
) -> None:
    """Scaffold a new driver package from the copier template."""
    from rosaos.scaffold import new_driver_command

    raise typer.Exit(
        new_driver_command(
            name=name,
            title=title,
            description=description,
            concurrency=concurrency,
            author=author,
            dest=dest,
            defaults=defaults,
        )
    )


def main() -> None:
    """Console-script entry point."""
    try:
        app()
    except KeyboardInterrupt:
        sys.exit(130)


if __name__ == "__main__":
    main()
