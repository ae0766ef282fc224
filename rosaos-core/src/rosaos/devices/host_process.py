"""The supervisor's handle on a device host process: spawn it, read its handshake, stop it."""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import signal
import sys
from collections.abc import Awaitable, Callable, Sequence
from pathlib import Path
from typing import Any

from rosaos.clock import LOOP_CLOCK, Clock
from rosaos.devices.heartbeat import is_tick
from rosaos.devices.host import HostJob
from rosaos.devices.host_logging import open_rotated_log
from rosaos.devices.host_zygote import ForkedHost
from rosaos.devices.host_zygote import take as zygote_take
from rosaos.drivers import DeviceError

log = logging.getLogger("rosaos.devices.host")


class HostProcess:
    """A running device host, seen from the supervisor: spawn it, read its handshake, stop it."""

    def __init__(self, process: asyncio.subprocess.Process | ForkedHost, log_file: Path) -> None:
        self.process = process
        self.log_file = log_file
        """The host's stderr: driver output, uvicorn warnings, tracebacks."""
        self.url = ""
        self.urls: dict[str, str] = {}
        """Per instance, for a host serving several (:mod:`rosaos.devices.host_batch`)."""
        self.errors: dict[str, str] = {}
        """Instances of a batch that could not start, and why."""
        self.last_tick = 0.0
        """When the host's last heartbeat line came (:mod:`rosaos.devices.heartbeat`), on ``clock``."""
        self.clock: Clock = LOOP_CLOCK
        """What ``last_tick`` is read on: the supervisor's clock, which its checks compare it with."""
        self._ticks: asyncio.Task[None] | None = None
        self._joining: dict[str, asyncio.Future[dict[str, Any]]] = {}
        """Instances sent to a running shared host (:meth:`join`), waiting for their line."""

    def follow_heartbeat(self, clock: Clock = LOOP_CLOCK) -> None:
        """Read the host's heartbeat lines from now on (after the handshake), into ``last_tick``."""
        self.clock = clock
        self.last_tick = clock.now()
        self._ticks = asyncio.create_task(self._read_ticks())

    async def _read_ticks(self) -> None:
        stdout = self.process.stdout
        assert stdout is not None
        while line := await stdout.readline():  # any line is a sign of life
            self.last_tick = self.clock.now()
            if line.startswith(b'{"instance"'):  # the answer of an instance that joined late
                reply = _reply(line)
                waiting = self._joining.pop(str(reply.get("instance")), None)
                if waiting is not None and not waiting.done():
                    waiting.set_result(reply)
        for waiting in self._joining.values():  # the host exited: nobody will answer
            if not waiting.done():
                waiting.set_result({"error": "the host exited before the instance started"})

    async def join(self, job: HostJob, start_timeout: float) -> str:
        """Serve one more instance in this running shared host; its URL, or DeviceError saying why not.

        For a driver that starts in the background (the Reachy simulator): it joins once the
        others serve, so its boot holds up neither them nor ``rosaos up``.
        """
        stdin = self.process.stdin
        assert stdin is not None, "only a host spawned by this supervisor can take more jobs"
        if self._ticks is None or self._ticks.done():
            raise DeviceError(f"{job.instance}: the shared host is not running; see {self.log_file}")
        answer: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self._joining[job.instance] = answer
        try:
            stdin.write(job.model_dump_json().encode() + b"\n")
            await stdin.drain()
            async with asyncio.timeout(start_timeout):
                reply = await answer
        except TimeoutError:
            raise DeviceError(
                f"{job.instance} did not become ready within {start_timeout:g} s; see {self.log_file}"
            ) from None
        except (ConnectionError, RuntimeError) as error:  # the host is gone: its pipe is closed
            raise DeviceError(f"{job.instance}: the host is gone ({error}); see {self.log_file}") from None
        finally:
            self._joining.pop(job.instance, None)
        if "url" not in reply:
            raise DeviceError(f"{reply.get('error') or 'no answer'} (log: {self.log_file})")
        self.urls[job.instance] = str(reply["url"])
        return self.urls[job.instance]

    @classmethod
    async def spawn(
        cls, job: HostJob, log_file: Path, start_timeout: float, stop_grace: float, clock: Clock = LOOP_CLOCK
    ) -> HostProcess:
        """Start a host for ``job`` and wait for its ready line; DeviceError says why it did not come up."""
        host = await cls._start(log_file)
        try:
            reply = await host._handshake(job.model_dump_json(), 1, start_timeout)
        except BaseException:  # including cancellation: never leave a half-started host behind
            await host.stop(stop_grace)
            raise
        if "url" not in reply[0]:
            await host.stop(stop_grace)
            reason = reply[0].get("error") or await asyncio.to_thread(_tail, log_file)
            raise DeviceError(f"{reason} (log: {log_file})")
        host.url = str(reply[0]["url"])
        host.follow_heartbeat(clock)
        return host

    @classmethod
    async def spawn_batch(
        cls,
        jobs: Sequence[HostJob],
        log_file: Path,
        start_timeout: float,
        stop_grace: float,
        on_ready: Callable[[HostProcess, str, str], Awaitable[None]] | None = None,
        clock: Clock = LOOP_CLOCK,
    ) -> HostProcess:
        """Start one host for several instances; ``urls`` has those that serve, ``errors`` the rest.

        ``on_ready(host, instance, url)`` is awaited as each instance's ready line arrives, so the
        first of a hundred instances can be used while the hundredth still starts.
        DeviceError when none of them came up (the host is stopped then). More instances may
        :meth:`join` it later.
        """
        from rosaos.devices.host_batch import HostBatch

        host = await cls._start(log_file)

        async def arrived(reply: dict[str, Any]) -> None:
            name = str(reply.get("instance", ""))
            if "url" not in reply:
                host.errors[name] = str(reply.get("error") or "no answer")
                return
            host.urls[name] = str(reply["url"])
            if on_ready is not None:
                await on_ready(host, name, host.urls[name])

        try:
            await host._handshake(
                HostBatch(jobs=list(jobs)).model_dump_json(), len(jobs), start_timeout, arrived
            )
        except BaseException:
            await host.stop(stop_grace)
            raise
        for job in jobs:
            if job.instance not in host.urls and job.instance not in host.errors:
                host.errors[job.instance] = f"the host did not report it (log: {log_file})"
        if not host.urls:
            await host.stop(stop_grace)
            tail = await asyncio.to_thread(_tail, log_file)
            raise DeviceError(f"no instance of the shared host started: {tail} (log: {log_file})")
        host.follow_heartbeat(clock)
        return host

    @classmethod
    async def _start(cls, log_file: Path) -> HostProcess:
        log_handle = await asyncio.to_thread(open_rotated_log, log_file)
        process: asyncio.subprocess.Process | ForkedHost | None = None
        try:
            # ``rosaos up``'s first host is forked from the kernel (rosaos.devices.host_zygote).
            if (zygote := zygote_take()) is not None:
                process = await zygote.become(log_handle.fileno())
            if process is None:
                process = await asyncio.create_subprocess_exec(
                    sys.executable,
                    "-P",  # the working directory must not shadow a module (a stray h2.py)
                    "-m",
                    "rosaos.devices.host",
                    stdin=asyncio.subprocess.PIPE,
                    stdout=asyncio.subprocess.PIPE,
                    stderr=log_handle,
                    # Its own process group: Ctrl-C in the terminal reaches the supervisor only, which
                    # then stops hosts in order; killpg also reaches anything a driver spawned.
                    start_new_session=True,
                )
        finally:
            log_handle.close()
        return cls(process, log_file)

    async def _handshake(
        self,
        job: str,
        lines: int,
        start_timeout: float,
        arrived: Callable[[dict[str, Any]], Awaitable[None]] | None = None,
    ) -> list[dict[str, Any]]:
        stdin, stdout = self.process.stdin, self.process.stdout
        assert stdin is not None
        assert stdout is not None
        # The job goes over stdin, which then stays open: the host exits when it sees EOF, so a
        # supervisor that dies hard leaves no orphan hosts behind.
        stdin.write(job.encode() + b"\n")
        await stdin.drain()
        replies: list[dict[str, Any]] = []
        loop = asyncio.get_running_loop()
        try:
            # The budget is per instance: it starts again at each reply, so a host that serves
            # three hundred instances, a few at a time, is not cut off while it makes progress.
            async with asyncio.timeout(start_timeout) as budget:
                while len(replies) < lines:
                    line = await stdout.readline()
                    if not line.strip():  # the host exited
                        break
                    reply = _reply(line)
                    if not is_tick(reply):  # a beat while other instances still start
                        replies.append(reply)
                        budget.reschedule(loop.time() + start_timeout)
                        if arrived is not None:
                            await arrived(reply)
        except TimeoutError:
            raise DeviceError(
                f"the host did not become ready within {start_timeout:g} s; see {self.log_file}"
            ) from None
        return replies or [{}]

    @property
    def pid(self) -> int:
        return self.process.pid

    async def wait(self) -> int:
        """Wait for the host to exit; its return code (negative: killed by that signal)."""
        return await self.process.wait()

    async def exit_reason(self) -> str:
        """Why the host exited, for the status: the signal, or the code and the log's last lines."""
        code = self.process.returncode
        if code is not None and code < 0:
            return f"host was killed by {signal.Signals(-code).name}"
        tail = await asyncio.to_thread(_tail, self.log_file)
        return f"host exited with code {code}" + (f": {tail}" if tail else "")

    async def stop(self, grace: float) -> None:
        """SIGTERM the host's process group, SIGKILL it after ``grace`` seconds; reap the host."""
        if self._ticks is not None:
            self._ticks.cancel()
        if self.process.returncode is None:
            _signal_group(self.pid, signal.SIGTERM)
            try:
                async with asyncio.timeout(grace):
                    await self.process.wait()
            except TimeoutError:
                log.warning("host %s did not stop within %g s; killing it", self.pid, grace)
        # Whatever the host left in its group (a simulator it spawned) goes too.
        _signal_group(self.pid, signal.SIGKILL)
        await self.process.wait()


def _reply(line: bytes) -> dict[str, Any]:
    try:
        reply = json.loads(line)
    except ValueError:
        return {"error": f"unexpected output from the host: {line[:200]!r}"}
    return reply if isinstance(reply, dict) else {}


def _tail(path: Path, lines: int = 3) -> str:
    """The last lines of a host's log: usually the reason it died."""
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return ""
    return " | ".join(line.strip() for line in text.strip().splitlines()[-lines:])


def _signal_group(pid: int, sig: signal.Signals) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pid, sig)
