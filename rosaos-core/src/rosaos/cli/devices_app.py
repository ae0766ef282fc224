"""``rosaos devices ...``: list, check and log in the device instances of the world."""

from __future__ import annotations

from typing import Annotated

import typer

from rosaos.cli.options import AnswerTimeoutOption, ConfigOption, JsonOption, StartTimeoutOption

devices_app = typer.Typer(help="Inspect and check the device instances of the world.", no_args_is_help=True)


@devices_app.command("list")
def devices_list(
    config: ConfigOption = None,
    json_output: JsonOption = False,
    check: Annotated[
        bool, typer.Option("--check/--no-check", help="Health-check each instance (get_state).")
    ] = True,
    timeout: AnswerTimeoutOption = 5.0,
    start_timeout: StartTimeoutOption = 60.0,
) -> None:
    """List the device instances: driver, package, concurrency, backend, URL and health.

    Exits 0 even when a device is unhealthy (the listing says so); 2 for a configuration error.
    """
    from rosaos.cli.device_commands import list_devices

    raise typer.Exit(
        list_devices(
            config, json_output=json_output, check=check, timeout=timeout, start_timeout=start_timeout
        )
    )


@devices_app.command("check")
def devices_check(
    name: Annotated[str, typer.Argument(help="Instance name, e.g. kitchen_light.")],
    config: ConfigOption = None,
    json_output: JsonOption = False,
    timeout: AnswerTimeoutOption = 10.0,
    start_timeout: StartTimeoutOption = 60.0,
) -> None:
    """Connect to one instance, call get_state and print it. Non-zero exit with the reason if it fails."""
    from rosaos.cli.device_commands import check_device

    raise typer.Exit(
        check_device(name, config, json_output=json_output, timeout=timeout, start_timeout=start_timeout)
    )


@devices_app.command("login")
def devices_login(
    name: Annotated[str, typer.Argument(help="Instance name, e.g. spotify.")],
    config: ConfigOption = None,
) -> None:
    """Log an instance in to its cloud account (e.g. spotify): prints a URL, reads the pasted answer."""
    from rosaos.config import ConfigError, load_config
    from rosaos.devices.world import build_world
    from rosaos.plugins import load_drivers

    try:
        settings = load_config(config)
        instance = build_world(settings, load_drivers()).get(name)
    except (ConfigError, KeyError) as error:
        typer.echo(f"error: {error.args[0] if error.args else error}", err=True)
        raise typer.Exit(2) from None
    if instance.spec.login is None:
        typer.echo(f"driver {instance.spec.name!r} needs no login; {name} is ready as configured")
        raise typer.Exit(0)
    if instance.is_remote:
        typer.echo(f"error: {name} is served on another machine; log in there", err=True)
        raise typer.Exit(1)
    raise typer.Exit(instance.spec.login(instance.context(settings.data_dir)))
