"""``rosaos ...``: the typer app. It declares each command's options and calls the command's function.

Commands import their modules lazily so ``rosaos --help`` stays fast.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Literal

import typer

from rosaos import __version__
from rosaos.cli.devices_app import devices_app
from rosaos.cli.memory_app import memory_app, places_app
from rosaos.cli.options import (
    BaseUrlOption,
    ConfigOption,
    JsonOption,
    ModelNameOption,
    ModelOption,
    ProcessModelOption,
    UrlOption,
)

app = typer.Typer(
    name="rosaos",
    help="rosaOS: an agentic operating system for embodied LLMs.",
    no_args_is_help=True,
    rich_markup_mode="rich",
    pretty_exceptions_enable=False,
)
app.add_typer(devices_app, name="devices")
app.add_typer(places_app, name="places")
app.add_typer(memory_app, name="memory")


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


@app.command("serve-device")
def serve_device(
    name: Annotated[str, typer.Argument(help="Instance name from the config (or the demo world).")],
    config: ConfigOption = None,
    host: Annotated[str, typer.Option(help="Address to bind. Loopback unless you mean it.")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="TCP port (0 picks a free one).", min=0, max=65535)] = 0,
    allow_host: Annotated[
        list[str] | None,
        typer.Option(
            help="A Host name other machines reach this by (repeatable); loopback and --host always work.",
        ),
    ] = None,
) -> None:
    """Serve one instance's MCP server over streamable HTTP, behind the bearer token."""
    from rosaos.cli.device_commands import serve_device_command

    raise typer.Exit(serve_device_command(name, config, host=host, port=port, allow_hosts=allow_host or []))


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


@app.command("up")
def up(
    config: ConfigOption = None,
    model: ModelOption = None,
    process_model: ProcessModelOption = None,
    base_url: BaseUrlOption = None,
    model_name: ModelNameOption = None,
    host: Annotated[
        str | None, typer.Option(help="Address for the API and web page (default 127.0.0.1).")
    ] = None,
    port: Annotated[
        int | None, typer.Option(help="Port for the API and web page (default 8765).", min=0)
    ] = None,
    pool_size: Annotated[int | None, typer.Option(help="Warm worker processes (default 2).", min=0)] = None,
) -> None:
    """Start the devices, the kernel, the worker pool and the web page; print the page's URL."""
    from rosaos.cli.up_command import model_overrides, up_command

    models = model_overrides(model, process_model, base_url, model_name)
    raise typer.Exit(up_command(config, host=host, port=port, pool_size=pool_size, models=models))


@app.command("chat")
def chat(
    message: Annotated[
        str | None, typer.Option("--message", "-m", help="Send one message and exit (scripts).")
    ] = None,
    wait: Annotated[
        bool,
        typer.Option(
            "--wait",
            help="With -m: wait for the reply and every process it starts. Exit 0 if it was done or "
            "answered; 1 if something failed or was refused; 4 if nothing was done because it was "
            "not understood or waits for your answer (the reason is on stderr).",
        ),
    ] = False,
    timeout: Annotated[
        float, typer.Option(help="With --wait: seconds to wait before giving up (exit 3).")
    ] = 60.0,
    json_output: JsonOption = False,
    config: ConfigOption = None,
    url: UrlOption = None,
) -> None:
    """Chat with the running kernel: a REPL, or one message with -m."""
    from rosaos.frontends.chat import chat_command
    from rosaos.kernel.api.kernel_client import KernelClient

    def client() -> KernelClient:
        from rosaos.config import load_config

        return KernelClient.from_config(load_config(config), url=url)

    raise typer.Exit(chat_command(client, message, wait, timeout, json_output))


@app.command("voice")
def voice(
    wav: Annotated[
        Path | None,
        typer.Option(
            "--wav",
            help="Listen to a 16 kHz mono WAV file instead (other PCM WAVs are converted); exit when done.",
            dir_okay=False,
        ),
    ] = None,
    source: Annotated[
        str | None,
        typer.Option("--source", help="mic or reachy (default: \\[voice] source, else mic)."),
    ] = None,
    url: UrlOption = None,
    config: ConfigOption = None,
    json_output: Annotated[
        bool, typer.Option("--json", help="Print one JSON object per step (heard, sent, ...).")
    ] = False,
) -> None:
    """Listen for the wake phrase and speak to the kernel: VAD, speech-to-text, POST /stt.

    Offline by default (Silero VAD, Moonshine); needs the voice extra: pip install 'rosaos\\[voice]'.
    """
    if wav is not None and source is not None:
        typer.echo("error: give --wav FILE or --source, not both", err=True)
        raise typer.Exit(2)
    if source not in (None, "mic", "reachy"):
        typer.echo(f"error: --source must be mic or reachy, not {source!r}", err=True)
        raise typer.Exit(2)
    try:
        from rosaos.frontends.voice.command import voice_command
    except ImportError as error:
        typer.echo(
            f"error: rosaos voice needs the voice extra ({error}): pip install 'rosaos[voice]'", err=True
        )
        raise typer.Exit(1) from None

    chosen: Literal["mic", "reachy"] | None = (
        "reachy" if source == "reachy" else "mic" if source == "mic" else None
    )
    raise typer.Exit(voice_command(config, wav, chosen, url, json_output))


@app.command("ps")
def ps(
    config: ConfigOption = None,
    url: UrlOption = None,
    json_output: JsonOption = False,
    all_processes: Annotated[bool, typer.Option("--all", "-a", help="Include ended processes.")] = False,
    timers: Annotated[
        bool,
        typer.Option("--timers", "-t", help="List the timers instead (with --all, fired and cancelled too)."),
    ] = False,
) -> None:
    """List the kernel's processes: id, state, devices held, age, task. --timers: its timers."""
    if timers:
        from rosaos.timers.timer_commands import timers_command

        raise typer.Exit(timers_command(config, url, json_output, all_processes))
    from rosaos.cli.process_commands import ps_command

    raise typer.Exit(ps_command(config, url, json_output, all_processes))


@app.command("ready")
def ready(
    config: ConfigOption = None,
    url: UrlOption = None,
    json_output: JsonOption = False,
    timeout: Annotated[
        float, typer.Option("--timeout", metavar="SECONDS", min=0, help="Give up after this long.")
    ] = 120.0,
) -> None:
    """Wait until the running kernel's devices have started and its workers are warm (for scripts).

    Exits 0 once ready, 1 if not within --timeout (it says what still starts), 2 for a bad config.
    """
    from rosaos.cli.ready_command import ready_command

    raise typer.Exit(ready_command(config, url, timeout, json_output))


@app.command("log")
def log(
    config: ConfigOption = None,
    url: UrlOption = None,
    json_output: JsonOption = False,
    device: Annotated[str | None, typer.Option("--device", "-d", help="Only this device's calls.")] = None,
    process: Annotated[
        int | None, typer.Option("--process", "-p", help="Only this process's calls.", min=1)
    ] = None,
    since: Annotated[
        str | None, typer.Option("--since", "-s", help="Only since: 30s, 10m, 2h, 1d ago, or an ISO time.")
    ] = None,
    limit: Annotated[int, typer.Option("--limit", "-n", help="The newest this many.", min=1, max=2000)] = 200,
) -> None:
    """Show the activity log: every tool call of the processes, its result and the safety decision."""
    from rosaos.cli.log_command import log_command

    raise typer.Exit(log_command(config, url, device, process, since, limit, json_output))


@app.command("open")
def open_page(
    config: ConfigOption = None,
    url: UrlOption = None,
    json_output: JsonOption = False,
    browser: Annotated[
        bool, typer.Option("--browser", "-b", help="Also open the link in a web browser.")
    ] = False,
) -> None:
    """Print a fresh one-time login link for the web page of the running kernel."""
    from rosaos.cli.open_command import open_command

    raise typer.Exit(open_command(config, url, browser, json_output))


@app.command("kill")
def kill(
    process_id: Annotated[int, typer.Argument(help="Process id, as `rosaos ps` shows it.", min=1)],
    config: ConfigOption = None,
    url: UrlOption = None,
    json_output: JsonOption = False,
    timer: Annotated[
        bool, typer.Option("--timer", help="The id is a timer's (`rosaos ps --timers`): cancel it.")
    ] = False,
) -> None:
    """Terminate a process; its device leases are released. --timer: cancel a timer instead."""
    if timer:
        from rosaos.timers.timer_commands import cancel_timer_command

        raise typer.Exit(cancel_timer_command(config, url, process_id, json_output))
    from rosaos.cli.process_commands import kill_command

    raise typer.Exit(kill_command(config, url, process_id, json_output))


@app.command("estop")
def estop(
    reset: Annotated[bool, typer.Option("--reset", help="Unlatch: allow processes to run again.")] = False,
    reason: Annotated[
        str, typer.Option(help="Why, for the log and the web page.")
    ] = "requested from the CLI",
    config: ConfigOption = None,
    url: UrlOption = None,
    json_output: JsonOption = False,
) -> None:
    """Emergency stop: kill every process, put every device in its safe state, refuse new work until reset."""
    from rosaos.cli.process_commands import estop_command

    raise typer.Exit(estop_command(config, url, reset, reason, json_output))


@app.command("bench")
def bench(
    paths: Annotated[
        list[Path] | None,
        typer.Argument(
            help="Task files, or directories of them (e.g. ../shared/bench/tasks).", show_default=False
        ),
    ] = None,
    model: ModelOption = None,
    process_model: ProcessModelOption = None,
    base_url: BaseUrlOption = None,
    model_name: ModelNameOption = None,
    repeat: Annotated[
        int, typer.Option(help="Run each task N times and report pass^k for k = 1..N.", min=1, max=100)
    ] = 1,
    tasks: Annotated[
        list[str] | None,
        typer.Option(
            "--tasks", "-t", help="Only tasks whose id matches this glob (repeatable), e.g. 'home-*'."
        ),
    ] = None,
    json_output: Annotated[
        bool, typer.Option("--json", help="Print the result as JSON instead of tables.")
    ] = False,
    out: Annotated[
        Path | None, typer.Option("--out", help="Also write the JSON result to this file.", dir_okay=False)
    ] = None,
    fail_under: Annotated[
        float | None,
        typer.Option(help="Exit 1 when the success rate is below this (0-1), for CI.", min=0.0, max=1.0),
    ] = None,
    config: ConfigOption = None,
) -> None:
    """Run task files on simulators through the full system and score them.

    Each task's sentence is posted as [User said]; once the kernel has settled, every device's
    state is checked against the task's expect. Exits 0 when the run completed (failures
    included), 1 below --fail-under, 2 for a usage or configuration error.
    """
    from rosaos.cli.bench_command import bench_command
    from rosaos.cli.up_command import model_overrides

    raise typer.Exit(
        bench_command(
            paths or [],
            config_path=config,
            models=model_overrides(model, process_model, base_url, model_name),
            repeat=repeat,
            patterns=tasks or [],
            json_output=json_output,
            out=out,
            fail_under=fail_under,
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
