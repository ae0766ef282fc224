"""The pool's side of the fork server: start it, ask it for workers, restart it when it dies.

:class:`ForkServer` runs ``python -m rosaos.processes.forkserver`` (see that module for the
protocol) next to the warm workers, and :meth:`ForkServer.spawn` returns a :class:`ForkedWorker`:
a one-off worker with the part of ``asyncio.subprocess.Process``'s interface the pool uses, started
in milliseconds instead of seconds. Anything that goes wrong raises :class:`ForkServerError`, and
the pool then spawns the worker the usual way, so a job is never lost to the fork server.

The fork server is the forked workers' parent: only it can see how they exit. If it dies while
some still run, the pool kills them (each reported crashed, killed by SIGKILL), since their ends
could not be reported otherwise. It is then restarted, after a delay that doubles while it keeps
dying before it is ready.

With ``park`` (per data directory; the kernel gives one), a server whose kernel died waits to be
adopted by the next kernel instead of exiting (:mod:`rosaos.processes.fork_parking`).
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import json
import logging
import os
import signal
import socket
from collections.abc import Awaitable, Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from rosaos.models.select import OPENAI_COMPATIBLE, PYTHON_PREFIX, ModelSpec
from rosaos.processes.fork_parking import adopt_parked, park_key
from rosaos.processes.zygote import take as zygote_take

log = logging.getLogger(__name__)

SPAWN_TIMEOUT = 10.0
"""Seconds to wait for the fork server's answer before spawning the worker the usual way."""
STOP_GRACE = 2.0
"""Seconds :meth:`ForkServer.stop` lets spawns in progress finish before killing the server."""
MAX_RESTART_DELAY = 30.0
KILL_WAIT = 5.0
"""Seconds to wait for the workers of a dead fork server to die once killed."""
MESSAGE_LIMIT = 64 * 1024


class ForkServerError(Exception):
    """The fork server could not start a worker; the pool spawns one the usual way instead."""


class ForkedWorker:
    """A worker forked by the fork server: ``pid``, ``stdin``, ``stdout``, ``returncode``, ``wait()``."""

    def __init__(
        self, pid: int, stdin: asyncio.StreamWriter, stdout: asyncio.StreamReader, exit: asyncio.Future[int]
    ) -> None:
        self._pid = pid
        self._stdin = stdin
        self._stdout = stdout
        self._exit = exit

    @property
    def pid(self) -> int:
        return self._pid

    @property
    def stdin(self) -> asyncio.StreamWriter:
        return self._stdin

    @property
    def stdout(self) -> asyncio.StreamReader:
        return self._stdout

    @property
    def returncode(self) -> int | None:
        """The exit code, negative for the killing signal; None while the worker runs."""
        return self._exit.result() if self._exit.done() else None

    async def wait(self) -> int:
        """Wait until the worker has exited and return its exit code."""
        # Shielded: a caller's timeout must not cancel the one future every waiter shares.
        return await asyncio.shield(self._exit)


class ForkServer:
    """Runs the fork server for a pool: ``python`` with ``env``, importing ``preload`` modules ahead."""

    def __init__(
        self, python: str, env: Mapping[str, str], preload: Sequence[str] = (), park: str | None = None
    ) -> None:
        self.python = python
        self.env = dict(env)
        self.preload = list(preload)
        self.park = park
        """The name to park under when the kernel dies, and to adopt a parked server by."""
        self.adopted = False
        """Whether the running server was adopted from a kernel that died, rather than started."""
        self.pid: int | None = None
        self.unusable: str | None = None
        """Why the fork server refused to serve (it is then not restarted)."""
        self._sock: socket.socket | None = None
        self._ready = False
        self._settled = asyncio.Event()
        """Set once the current server is ready or gone; start() waits on it."""
        self._requests: dict[int, asyncio.Future[tuple[int, asyncio.Future[int]]]] = {}
        self._children: dict[int, asyncio.Future[int]] = {}
        self._orphans: set[int] = set()
        """Workers forked for a request the pool gave up on; killed, their exits ignored."""
        self._request_ids = itertools.count(1)
        self._supervisor: asyncio.Task[None] | None = None
        self._stopping = False
        self._stop_requested = asyncio.Event()

    @property
    def ready(self) -> bool:
        """Whether a fork server is running and has finished its imports."""
        return self._ready

    def start(self) -> None:
        """Start the fork server in the background (it imports for seconds); see :meth:`wait_ready`."""
        self._stopping = False
        self._stop_requested.clear()
        self.unusable = None
        self._settled.clear()
        self._supervisor = asyncio.create_task(self._supervise(), name="rosaos-fork-server")

    async def wait_ready(self) -> bool:
        """Wait until the fork server is ready, or has died trying; return whether it is ready."""
        await self._settled.wait()
        return self._ready

    async def spawn(self, limit: int) -> ForkedWorker:
        """Fork a worker; its stdout reader has line limit ``limit``. Raises :class:`ForkServerError`."""
        if not self._ready or self._sock is None:
            raise ForkServerError("the fork server is not running")
        stdin_r, stdin_w = os.pipe()
        stdout_r, stdout_w = os.pipe()
        request = next(self._request_ids)
        answer = asyncio.get_running_loop().create_future()
        self._requests[request] = answer
        try:
            socket.send_fds(self._sock, [json.dumps({"spawn": request}).encode()], [stdin_r, stdout_w])
        except OSError as failure:
            self._requests.pop(request, None)
            _close(stdin_w, stdout_r)
            raise ForkServerError(f"cannot reach the fork server: {failure}") from None
        finally:
            _close(stdin_r, stdout_w)  # the fork server has its own copies now
        try:
            async with asyncio.timeout(SPAWN_TIMEOUT):
                pid, exit = await answer
        except BaseException as failure:
            self._requests.pop(request, None)
            _close(stdin_w, stdout_r)
            if isinstance(failure, TimeoutError):
                raise ForkServerError(f"no answer from the fork server in {SPAWN_TIMEOUT:g} s") from None
            raise
        try:
            return ForkedWorker(pid, *await _connect_pipes(stdin_w, stdout_r, limit), exit)
        except BaseException:
            _killpg(pid)
            raise

    async def stop(self) -> None:
        """Stop the fork server, once spawns in progress are answered; kill workers it still has."""
        self._stopping = True
        self._stop_requested.set()
        if self._requests:
            await asyncio.wait(list(self._requests.values()), timeout=STOP_GRACE)
        if self.pid is not None:
            _killpg(self.pid)
        if self._supervisor is not None:
            await self._supervisor
            self._supervisor = None

    # -- the server process -------------------------------------------------------------------

    async def _supervise(self) -> None:
        failures = 0
        while not self._stopping and self.unusable is None:
            was_ready, returncode = await self._run_once()
            if self._stopping or self.unusable is not None:
                break
            failures = 0 if was_ready else failures + 1
            delay = min(MAX_RESTART_DELAY, 0.5 * 2**failures)
            log.error(
                "the fork server exited (%s)%s; restarting it in %g s",
                "exit code unknown" if returncode is None else f"exit code {returncode}",
                "" if was_ready else " while starting up",
                delay,
            )
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._stop_requested.wait(), delay)

    async def _run_once(self) -> tuple[bool, int | None]:
        """Run one fork server until it exits; return whether it became ready, and its exit code.

        The first one is adopted, when a parked server of the same data directory fits."""
        zygote = zygote_take()
        adopted = await self._adopt() if self.park is not None and not self.adopted else None
        self.adopted = adopted is not None
        if adopted is not None:
            if zygote is not None:
                zygote.discard()
            ours, pid = adopted
            return await self._watch(ours, pid, None)
        parking = (self.park, self._key()) if self.park is not None else None
        if zygote is not None and (forked := zygote.become(self.python, self.env, self.preload, parking)):
            return await self._watch(forked, zygote.pid, None, zygote.reap)
        try:
            ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        except OSError as failure:  # not on Linux
            self.unusable = f"this system has no UNIX SOCK_SEQPACKET sockets ({failure.strerror})"
            log.warning("one-off workers start without the fork server: %s", self.unusable)
            self._settled.set()
            return False, None
        park = ["--park", self.park, self._key()] if self.park is not None else []
        try:
            process = await asyncio.create_subprocess_exec(
                self.python,
                "-P",  # the working directory must not shadow a module (a stray h2.py)
                "-m",
                "rosaos.processes.forkserver",
                str(theirs.fileno()),
                *park,
                *self.preload,
                stdin=asyncio.subprocess.DEVNULL,
                stdout=asyncio.subprocess.DEVNULL,
                env=self.env,
                pass_fds=(theirs.fileno(),),
                start_new_session=True,
            )
        except OSError as failure:
            ours.close()
            log.error("cannot start the fork server with %s: %s", self.python, failure.strerror)
            self._settled.set()
            return False, None
        finally:
            theirs.close()
        if self._stopping:  # stop() ran while the process was being started
            _killpg(process.pid)
        return await self._watch(ours, process.pid, process)

    async def _watch(
        self,
        ours: socket.socket,
        pid: int,
        process: asyncio.subprocess.Process | None,
        reap: Callable[[], Awaitable[int | None]] | None = None,
    ) -> tuple[bool, int | None]:
        """Serve the pool with the server ``pid`` on ``ours`` until it exits (or its socket closes:
        an adopted server is not this process's child, and its exit code is not known; one forked
        from the kernel is reaped by ``reap``)."""
        self.pid = pid
        loop = asyncio.get_running_loop()
        closed = loop.create_future()
        ours.setblocking(False)
        self._sock = ours
        loop.add_reader(ours.fileno(), self._read, ours, closed)
        was_ready = False
        try:
            exited = asyncio.ensure_future(process.wait()) if process is not None else None
            await asyncio.wait([closed, *([exited] if exited else [])], return_when=asyncio.FIRST_COMPLETED)
            was_ready = self._ready
        finally:
            self._read(ours, closed)  # the exits it sent before it died
            loop.remove_reader(ours.fileno())
            ours.close()
            self._sock = None
            self._ready = False
            _killpg(pid)
            returncode = await process.wait() if process is not None else await reap() if reap else None
            self.pid = None
            await self._lost()
            self._settled.set()
        return was_ready, returncode

    def _key(self) -> str:
        return park_key(self.python, self.env, self.preload)

    async def _adopt(self) -> tuple[socket.socket, int] | None:
        """A parked fork server of this data directory, adopted: its socket and pid; or None."""
        assert self.park is not None
        adopted = await adopt_parked(self.park, self._key())
        if adopted is not None:
            self._on_message({"event": "ready"})
        return adopted

    def _read(self, sock: socket.socket, closed: asyncio.Future[None]) -> None:
        while True:
            try:
                message = sock.recv(MESSAGE_LIMIT)
            except BlockingIOError:
                return
            except OSError:
                message = b""
            if not message:
                if not closed.done():
                    closed.set_result(None)
                return
            try:
                self._on_message(json.loads(message))
            except (ValueError, KeyError, TypeError) as failure:
                log.error("the fork server sent a message that is not understood: %s", failure)

    def _on_message(self, message: dict[str, Any]) -> None:
        event = message["event"]
        if event == "ready":
            self._ready = True
            self._settled.set()
        elif event == "spawned":
            pid = message["pid"]
            self._children[pid] = exit = asyncio.get_running_loop().create_future()
            answer = self._requests.pop(message["spawn"], None)
            if answer is None or answer.done():
                self._orphans.add(pid)
                _killpg(pid)
            else:
                answer.set_result((pid, exit))
        elif event == "failed":
            answer = self._requests.pop(message["spawn"], None)
            if answer is not None and not answer.done():
                answer.set_exception(ForkServerError(message["error"]))
        elif event == "exited":
            ended = self._children.pop(message["pid"], None)
            self._orphans.discard(message["pid"])
            if ended is not None and not ended.done():
                ended.set_result(message["returncode"])
        elif event == "unusable":
            self.unusable = message["error"]
            log.warning("one-off workers start without the fork server: %s", self.unusable)

    async def _lost(self) -> None:
        """The server is gone: fail the spawns it did not answer, kill the workers it cannot reap."""
        for answer in self._requests.values():
            if not answer.done():
                answer.set_exception(ForkServerError("the fork server exited"))
        self._requests.clear()
        running = [pid for pid, exit in self._children.items() if pid not in self._orphans]
        if running and not self._stopping:
            log.error(
                "the fork server died; killing its workers %s, whose exits it can no longer report", running
            )
        children, self._children = self._children, {}
        self._orphans.clear()
        for pid in children:
            _killpg(pid)
        # They are no longer anyone's children here: watch them die instead of reaping them.
        for _ in range(int(KILL_WAIT / 0.01)):
            if not any(_running(pid) for pid in children):
                break
            await asyncio.sleep(0.01)
        for exit in children.values():
            if not exit.done():
                exit.set_result(-signal.SIGKILL)


async def _connect_pipes(
    stdin_w: int, stdout_r: int, limit: int
) -> tuple[asyncio.StreamWriter, asyncio.StreamReader]:
    """Stream objects for the pool's ends of a worker's pipes, as asyncio's subprocesses have."""
    loop = asyncio.get_running_loop()
    stdin_pipe, stdout_pipe = os.fdopen(stdin_w, "wb", buffering=0), os.fdopen(stdout_r, "rb", buffering=0)
    stdout = asyncio.StreamReader(limit=limit, loop=loop)
    try:
        reading, _ = await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(stdout), stdout_pipe)
    except BaseException:
        stdin_pipe.close()
        stdout_pipe.close()
        raise
    try:
        writing, protocol = await loop.connect_write_pipe(asyncio.streams.FlowControlMixin, stdin_pipe)
    except BaseException:
        reading.close()
        stdin_pipe.close()
        raise
    return asyncio.StreamWriter(writing, protocol, None, loop), stdout


def preload_modules(spec: ModelSpec) -> list[str]:
    """Modules that building ``spec``'s model imports, for the fork server to import ahead.

    A best guess: a module that does not exist is skipped by the fork server.
    """
    if spec.model is None:
        return []
    if spec.model.startswith(PYTHON_PREFIX):
        return [spec.model[len(PYTHON_PREFIX) :].partition(":")[0]]
    if spec.model == OPENAI_COMPATIBLE:
        return ["pydantic_ai.models.openai"]
    provider = spec.model.partition(":")[0].partition("-")[0]  # google-gla, openai-chat: the SDK's name
    return [f"pydantic_ai.models.{provider}"]


def _running(pid: int) -> bool:
    """Whether ``pid`` runs: it exists and is not a zombie (Linux; elsewhere it is taken as gone)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] not in ("Z", "X")


def _killpg(pid: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pid, signal.SIGKILL)


def _close(*fds: int) -> None:
    for fd in fds:
        with contextlib.suppress(OSError):
            os.close(fd)
