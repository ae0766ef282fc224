"""``rosaos devices list``, ``rosaos devices check`` and ``rosaos serve-device``: the device commands.

Each returns its exit code; :mod:`rosaos.cli` wires them to typer. A configuration that cannot
be used exits 2 with the reason (file, key, what is wrong) and no traceback.
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import json
import socket
import sys
from collections.abc import Callable, Coroutine, Sequence
from pathlib import Path
from typing import Any, TypeVar
from urllib.parse import urlsplit

from pydantic import BaseModel
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from rosaos.auth import bound_hosts, load_or_create_token, token_path
from rosaos.cli.console import console
from rosaos.config import ConfigError, RosaosConfig, load_config
from rosaos.devices.health import CheckBudget, CheckResult, HealthCheck, Route, Via, find_routes
from rosaos.devices.host import START_TIMEOUT, install_stop_signals, serve_until_stopped
from rosaos.devices.progress import CheckProgress, wants_progress
from rosaos.devices.run_files import devices_not_ready, record_served_device, served_devices
from rosaos.devices.serve import ServedDevice
from rosaos.devices.world import DeviceInstance, World, build_world
from rosaos.drivers import DeviceError
from rosaos.plugins import DriverRegistry, load_drivers

LIST_TIMEOUT = 5.0
"""Default seconds each instance's ``get_state`` may take in ``devices list`` (``--timeout``)."""
CHECK_TIMEOUT = 10.0
"""Default seconds ``get_state`` may take in ``devices check`` (``--timeout``)."""

T = TypeVar("T")


class DeviceRow(BaseModel):
    """One line of ``rosaos devices list`` (one object of its ``--json`` output)."""

    instance: str
    driver: str
    package: str
    version: str
    concurrency: str
    backend: str
    url: str | None
    """Where it is served: by ``rosaos up``/``serve-device`` here, or the remote URL; None if not served."""
    health: str
    state: dict[str, Any] | None = None
    """The ``get_state`` answer, when the instance was checked."""
    via: Via | None = None
    """How it is (or would be) checked, as in ``devices check --json``; None for a placeholder."""


def _stderr() -> Console:
    return console(stderr=True)


def _load(config_path: Path | None) -> tuple[RosaosConfig, DriverRegistry, World]:
    config = load_config(config_path)
    registry = load_drivers()
    return config, registry, build_world(config, registry)


def _load_or_report(config_path: Path | None) -> tuple[RosaosConfig, DriverRegistry, World] | None:
    try:
        return _load(config_path)
    except (ConfigError, KeyError) as error:
        message = error.args[0] if isinstance(error, KeyError) and error.args else str(error)
        print(f"error: {message}", file=sys.stderr)
        return None


def _run_checks(
    checks: Callable[[HealthCheck], Coroutine[Any, Any, T]],
    names: list[str],
    data_dir: Path,
    budget: CheckBudget,
    json_output: bool,
) -> T:
    """Run ``checks`` on a fresh event loop, with a progress line on stderr for a terminal user."""
    stderr = _stderr()
    if not names or not wants_progress(json_output, stderr):
        return asyncio.run(checks(HealthCheck(data_dir, budget)))
    progress = CheckProgress(names)
    with progress.shown_on(stderr):
        return asyncio.run(checks(HealthCheck(data_dir, budget, progress.update)))


# --- rosaos devices list ------------------------------------------------------------------------


def list_devices(
    config_path: Path | None,
    json_output: bool = False,
    check: bool = True,
    timeout: float = LIST_TIMEOUT,
    start_timeout: float = START_TIMEOUT,
) -> int:
    """Print the world's instances with driver, package, concurrency, backend, URL and health.

    Instances are checked concurrently. One that nobody serves is started here and gets
    ``start_timeout`` seconds to start, then ``timeout`` seconds to answer ``get_state``.
    Exits 0 even when some device is unhealthy or unreachable: listing is informational, and the
    health column says what is wrong. Use ``rosaos devices check NAME`` for a pass/fail exit code.
    Exits 2 only when the configuration cannot be used.
    """
    loaded = _load_or_report(config_path)
    if loaded is None:
        return 2
    config, registry, world = loaded
    instances = list(world)
    checked = [i.name for i in instances if check and i.spec.implemented]
    budget = CheckBudget(answer=timeout, start=start_timeout)

    async def rows(health: HealthCheck) -> list[DeviceRow]:
        routes = await asyncio.to_thread(find_routes, instances, config.data_dir)
        return list(await asyncio.gather(*(_row(i, routes[i.name], health, check) for i in instances)))

    listed = _run_checks(rows, checked, config.data_dir, budget, json_output)
    if json_output:
        print(json.dumps([row.model_dump() for row in listed], indent=2, default=str))
    else:
        _print_table(listed, world)
    for broken in registry.broken:
        _stderr().print(
            f"[yellow]warning:[/] plugin {broken.plugin!r} ({broken.package}) is broken and was "
            f"skipped: {escape(broken.error)}"
        )
    return 0


async def _row(instance: DeviceInstance, route: Route, health: HealthCheck, check: bool) -> DeviceRow:
    info = instance.driver
    row = DeviceRow(
        instance=instance.name,
        driver=info.spec.name,
        package=info.package,
        version=info.version,
        concurrency=info.spec.concurrency,
        backend=instance.backend,
        url=route.url,
        health="not checked",
    )
    if not info.spec.implemented:
        row.health = "not implemented"
        return row
    row.via = route.via
    if not check:
        if route.entry is not None:
            row.health = f"{route.entry.status} (not checked)"
        elif route.via == "in-process":
            row.health = "not served"
        return row
    result = await health.check(instance, route)
    row.url, row.state = result.route.url, result.state
    if result.ok:
        row.health = "healthy (not served)" if route.via == "in-process" else "healthy"
    elif result.still_starting:
        row.health = f"starting: {result.error}"
    else:
        row.health = f"error: {result.error}"
    return row


HEALTH_COLOURS = {"healthy": "green", "error": "red", "starting": "yellow"}


def _print_table(rows: list[DeviceRow], world: World) -> None:
    title = "demo world (no rosaos.toml)" if world.is_demo else str(world.source)
    table = Table(title=f"Devices: {escape(title)}", title_justify="left")
    for column in ("Instance", "Driver", "Package", "Concurrency", "Backend", "URL", "Health"):
        table.add_column(column, overflow="fold")
    for row in rows:
        colour = next((c for word, c in HEALTH_COLOURS.items() if row.health.startswith(word)), "dim")
        table.add_row(
            row.instance,
            row.driver,
            f"{row.package} {row.version}",
            row.concurrency,
            row.backend,
            row.url or "-",
            f"[{colour}]{escape(row.health)}[/]",
        )
    console().print(table)


# --- rosaos devices check -----------------------------------------------------------------------


def check_device(
    name: str,
    config_path: Path | None,
    json_output: bool = False,
    timeout: float = CHECK_TIMEOUT,
    start_timeout: float = START_TIMEOUT,
) -> int:
    """Call one instance's get_state and print it; exit 1 with the reason when that fails.

    Goes to the served URL when ``rosaos up`` or ``rosaos serve-device`` serves it here (waiting
    up to ``start_timeout`` seconds while ``rosaos up`` is still starting it), to the URL of a
    remote instance, or else starts it in this process (``start_timeout`` seconds to start);
    ``get_state`` then has ``timeout`` seconds. The output says which.
    """
    loaded = _load_or_report(config_path)
    if loaded is None:
        return 2
    config, _, world = loaded
    try:
        instance = world.get(name)
    except KeyError as error:
        return _check_failed(name, None, None, str(error.args[0]), json_output)
    if not instance.spec.implemented:
        reason = (
            f"driver {instance.spec.name!r} ({instance.driver.package}) is not implemented yet: "
            "it is listed but cannot be served or checked"
        )
        return _check_failed(name, None, None, reason, json_output)
    route = find_routes([instance], config.data_dir)[name]
    budget = CheckBudget(answer=timeout, start=start_timeout)

    async def one(health: HealthCheck) -> CheckResult:
        return await health.check(instance, route)

    result = _run_checks(one, [name], config.data_dir, budget, json_output)
    via, url, entry = result.route.via, result.route.url, result.route.entry
    if result.error is not None:
        return _check_failed(name, via, url, result.error, json_output)
    state = result.state
    if json_output:
        print(json.dumps({"instance": name, "via": via, "url": url, "ok": True, "state": state}, indent=2))
        return 0
    where = {
        "served": f"served at {url} (pid {entry.pid if entry else '?'})",
        "remote": f"remote instance at {url}",
        "in-process": "in this process: it is not being served (start it with `rosaos up` "
        f"or `rosaos serve-device {name}`)",
    }[via]
    print(f"{name}: healthy, checked {where}")
    print(json.dumps(state, indent=2, default=str))
    return 0


def _check_failed(name: str, via: Via | None, url: str | None, reason: str, json_output: bool) -> int:
    if json_output:
        print(json.dumps({"instance": name, "via": via, "url": url, "ok": False, "error": reason}, indent=2))
    print(f"{name}: check failed: {reason}", file=sys.stderr)
    return 1


# --- rosaos serve-device ------------------------------------------------------------------------


def serve_device_command(
    name: str,
    config_path: Path | None,
    host: str = "127.0.0.1",
    port: int = 0,
    allow_hosts: Sequence[str] = (),
) -> int:
    """Serve one instance in the foreground over streamable HTTP, behind the token, until Ctrl-C."""
    loaded = _load_or_report(config_path)
    if loaded is None:
        return 2
    config, _, world = loaded
    try:
        instance = world.get(name)
    except KeyError as error:
        print(f"error: {error.args[0]}", file=sys.stderr)
        return 1
    if instance.is_remote:
        print(
            f"error: {name} is a remote instance ({instance.url}); run `rosaos serve-device {name}` "
            "on that machine, with a config where it is local",
            file=sys.stderr,
        )
        return 1
    if not instance.spec.implemented:
        print(
            f"error: driver {instance.spec.name!r} is not implemented yet; it cannot be served",
            file=sys.stderr,
        )
        return 1
    already = served_devices(config.data_dir).get(name)
    if already is not None:
        print(
            f"error: {name} is already served at {already.url} (pid {already.pid}); stop that first, "
            "so two copies of one device do not disagree",
            file=sys.stderr,
        )
        return 1
    owned = devices_not_ready(config.data_dir).get(name)
    if owned is not None:
        print(
            f"error: {name} belongs to the running `rosaos up` ({owned.status}); it starts and "
            "restarts it itself. Stop rosaos up first to serve it on its own",
            file=sys.stderr,
        )
        return 1
    if not _is_loopback(host):
        _stderr().print(
            f"[yellow]warning:[/] binding {escape(host)}, not loopback: anyone who can reach this "
            f"machine and holds the token can drive {name}. Keep the token secret and the network trusted."
        )
    token = load_or_create_token(config.data_dir)
    try:
        asyncio.run(_serve(instance, config.data_dir, token, host, port or instance.port or 0, allow_hosts))
    except DeviceError as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    return 0


async def _serve(
    instance: DeviceInstance, data_dir: Path, token: str, host: str, port: int, allow_hosts: Sequence[str]
) -> None:
    stop = asyncio.Event()
    install_stop_signals(stop)
    with contextlib.ExitStack() as records:

        def ready(served: ServedDevice) -> None:
            records.enter_context(record_served_device(data_dir, instance.name, served.url))
            backend = f"{instance.spec.name}, {instance.backend}"
            print(f"{instance.name} ({backend}) serving at {served.url}")
            print(f"token: {token_path(data_dir)} (send 'Authorization: Bearer <token>')")
            if not _is_loopback(host):
                port = urlsplit(served.url).port
                print(
                    f'other machines: url = "http://{socket.gethostname()}:{port}/mcp" and this token '
                    f"as token = ... in [devices.{instance.name}] of their rosaos.toml"
                )
                names = ", ".join(["loopback", *allow_hosts, *bound_hosts(host)])
                print(f"answers to Host: {names}; add the name other machines use with --allow-host NAME")
            print("Press Ctrl-C to stop.", flush=True)

        await serve_until_stopped(
            instance, data_dir, token, host, port, ready, stop, allowed_hosts=allow_hosts
        )
    print(f"{instance.name}: stopped", flush=True)


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False
