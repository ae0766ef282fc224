"""One device host: the subprocess that serves a single local instance (``python -m rosaos.devices.host``).

This module is the inside of that process (:func:`main`);
:class:`~rosaos.devices.host_process.HostProcess` is the handle the supervisor spawns and stops it
with, and :mod:`rosaos.devices.host_batch` serves several instances in one host.

The supervisor starts one host per local instance and writes a :class:`HostJob` as one JSON line
to its stdin (a job can also be given as the first argument, for debugging by hand). The host
resolves the driver, starts the backend, serves it over HTTP, and prints exactly one JSON line
on stdout: ``{"url": ..., "pid": ...}`` when ready, or ``{"error": ...}`` before exiting 1.
It then runs until SIGTERM/SIGINT, or until its stdin closes (the supervisor is gone), and
closes the backend on the way out.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import signal
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TextIO

from pydantic import BaseModel, ConfigDict, Field, SecretBytes, SecretStr, ValidationError
from pydantic_core import to_jsonable_python

from rosaos.config import format_validation_error
from rosaos.devices.heartbeat import beat
from rosaos.devices.host_logging import configure_host_logging
from rosaos.devices.serve import ServedDevice, open_device, serve_http
from rosaos.devices.world import DeviceInstance
from rosaos.drivers import BackendName, DeviceError
from rosaos.plugins import load_drivers

log = logging.getLogger("rosaos.devices.host")

START_TIMEOUT = 60.0
"""Default seconds a device may take to start: its backend starting and its server listening.

``rosaos up`` gives each host this long; ``devices list`` and ``devices check`` give an instance
they start themselves the same (``--start-timeout``)."""


class HostJob(BaseModel):
    """What a device host serves: one instance, fully resolved, plus where to listen."""

    model_config = ConfigDict(extra="forbid")

    instance: str
    driver: str
    backend: BackendName
    settings: dict[str, Any] = Field(default_factory=dict)
    """The driver's settings for this instance, as accepted by ``spec.settings``."""
    sim: dict[str, Any] = Field(default_factory=dict)
    description: str
    data_dir: Path
    host: str = "127.0.0.1"
    port: int = Field(default=0, ge=0, le=65535)
    """Port to bind; 0 picks a free one."""
    preferred_port: int | None = Field(default=None, ge=1, le=65535)
    """Try this port first and fall back to a free one: a restart keeps its URL when it can."""
    token_file: Path
    config_file: Path | None = None
    """The rosaos.toml the instance came from, for messages; None for the demo world."""
    heartbeat: float = Field(default=1.0, gt=0, le=60)
    """Seconds between heartbeat lines on stdout (:mod:`rosaos.devices.heartbeat`)."""

    @classmethod
    def for_instance(
        cls, instance: DeviceInstance, data_dir: Path, token_file: Path, config_file: Path | None, **kw: Any
    ) -> HostJob:
        """The job that serves ``instance``; settings keep their secrets (the job goes over a pipe)."""
        return cls(
            instance=instance.name,
            driver=instance.spec.name,
            backend=instance.backend,
            settings=_plain(instance.settings.model_dump(mode="python", by_alias=True)),
            sim=_plain(instance.sim),
            description=instance.description,
            data_dir=data_dir,
            token_file=token_file,
            config_file=config_file,
            **kw,
        )

    def resolve(self) -> DeviceInstance:
        """Rebuild the instance against the drivers installed here; DeviceError says what is wrong."""
        # Plugins are usually named after their driver: load just that one, so a host starts fast
        # and a broken unrelated plugin cannot stop it; fall back to loading them all.
        registry = load_drivers(allow={self.driver})
        if self.driver not in registry.drivers:
            registry = load_drivers()
        try:
            info = registry.get(self.driver)
        except KeyError as error:
            raise DeviceError(f"{self.instance}: {error.args[0]}") from None
        try:
            settings = info.spec.settings.model_validate(self.settings)
        except ValidationError as error:
            where = str(self.config_file) if self.config_file else "demo world"
            raise DeviceError(
                format_validation_error(where, error, prefix=f"devices.{self.instance}")
            ) from None
        return DeviceInstance(
            name=self.instance,
            driver=info,
            backend=self.backend,
            description=self.description,
            settings=settings,
            sim=dict(self.sim),
        )


def _plain(value: Any) -> Any:
    """JSON-ready data with secrets revealed: pydantic would otherwise write ``**********``."""
    if isinstance(value, SecretStr | SecretBytes):
        return _plain(value.get_secret_value())
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    if isinstance(value, list | tuple | set | frozenset):
        return [_plain(item) for item in value]
    return to_jsonable_python(value)


async def serve_until_stopped(
    instance: DeviceInstance,
    data_dir: Path,
    token: str,
    host: str,
    port: int,
    on_ready: Callable[[ServedDevice], None],
    stop: asyncio.Event,
    preferred_port: int | None = None,
    allowed_hosts: Sequence[str] = (),
) -> None:
    """Serve ``instance`` over HTTP, call ``on_ready`` once it accepts connections, run until ``stop``.

    Shared by the device host and ``rosaos serve-device``. The backend is closed on the way out,
    including when start-up fails.
    """
    async with open_device(instance, data_dir) as device, contextlib.AsyncExitStack() as stack:
        served: ServedDevice | None = None
        if preferred_port:
            try:
                served = await stack.enter_async_context(
                    serve_http(device.server, token, host, preferred_port, allowed_hosts)
                )
            except DeviceError:
                log.info("port %s is taken; %s gets a free port instead", preferred_port, instance.name)
        if served is None:
            served = await stack.enter_async_context(
                serve_http(device.server, token, host, port, allowed_hosts)
            )
        on_ready(served)
        stopper = asyncio.create_task(stop.wait())
        try:
            await asyncio.wait({stopper, served.task}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            stopper.cancel()
        if served.task.done() and not stop.is_set():
            served.task.result()  # surface the reason uvicorn stopped
            raise DeviceError(f"{instance.name}: the HTTP server stopped unexpectedly")


def install_stop_signals(stop: asyncio.Event) -> None:
    """SIGTERM and SIGINT set ``stop`` so the backend is closed cleanly instead of killed."""
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, stop.set)


async def stop_on_stdin_eof(stop: asyncio.Event) -> None:
    """Set ``stop`` when stdin closes: the supervisor died or let go, so no orphan host lingers."""
    loop = asyncio.get_running_loop()
    reader = asyncio.StreamReader()
    try:
        await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(reader), sys.stdin)
    except (ValueError, OSError):  # not a pipe (a terminal or a file): nobody to watch
        return
    while await reader.read(4096):
        pass
    stop.set()


class Handshake:
    """The one line a host owes its supervisor on stdout: ready (url, pid) or the error."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.sent = False

    def send(self, message: dict[str, Any]) -> None:
        """Write the line once; anything later (an error after ready) goes to the log only."""
        if self.sent:
            log.error("%s", message.get("error", message))
            return
        self.sent = True
        self.stream.write(json.dumps(message) + "\n")
        self.stream.flush()


async def run_job(job: HostJob, handshake: Handshake, watch_stdin: bool) -> int:
    """Serve ``job``, reporting readiness through ``handshake``; return the exit code."""
    stop = asyncio.Event()
    install_stop_signals(stop)
    watcher = asyncio.create_task(stop_on_stdin_eof(stop)) if watch_stdin else None
    ticker = asyncio.create_task(beat(handshake.stream, job.heartbeat)) if watch_stdin else None

    def ready(served: ServedDevice) -> None:
        handshake.send({"url": served.url, "pid": os.getpid()})
        log.info("%s (%s, %s) serving at %s", job.instance, job.driver, job.backend, served.url)

    try:
        token = job.token_file.read_text(encoding="utf-8").strip()
        if not token:
            raise DeviceError(f"token file {job.token_file} is empty")
        instance = job.resolve()
        await serve_until_stopped(
            instance, job.data_dir, token, job.host, job.port, ready, stop, job.preferred_port
        )
    except (DeviceError, OSError) as error:
        handshake.send({"error": str(error)})
        return 1
    except Exception as error:  # the supervisor shows the message; the traceback goes to the log
        log.exception("device host for %s failed", job.instance)
        handshake.send({"error": f"{type(error).__name__}: {error}"})
        return 1
    finally:
        for task in (watcher, ticker):
            if task is not None:
                task.cancel()
    return 0


def main(argv: list[str] | None = None) -> int:
    """Entry point: read the job (argv[1] or one stdin line), serve it, return the exit code."""
    argv = sys.argv if argv is None else argv
    configure_host_logging()
    # Keep the real stdout for the handshake line only; anything a driver prints goes to stderr,
    # so a chatty driver can neither corrupt the handshake nor fill a pipe nobody reads.
    reply = Handshake(os.fdopen(os.dup(sys.stdout.fileno()), "w", encoding="utf-8"))
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())
    from_stdin = len(argv) < 2
    raw = sys.stdin.readline() if from_stdin else argv[1]
    if raw.lstrip().startswith('{"jobs"'):  # several instances: rosaos.devices.host_batch
        from rosaos.devices.host_batch import BatchHandshake, HostBatch, run_batch

        try:
            batch = HostBatch.model_validate_json(raw)
        except ValidationError as error:
            reply.send({"error": f"invalid host job: {format_validation_error('job', error)}"})
            return 2
        return asyncio.run(run_batch(batch, BatchHandshake(reply.stream), watch_stdin=from_stdin))
    try:
        job = HostJob.model_validate_json(raw)
    except ValidationError as error:
        reply.send({"error": f"invalid host job: {format_validation_error('job', error)}"})
        return 2
    return asyncio.run(run_job(job, reply, watch_stdin=from_stdin))


if __name__ == "__main__":
    sys.exit(main())
