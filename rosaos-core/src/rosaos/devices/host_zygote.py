"""The first device host forked from the kernel, so the two share the pages of what both import.

A host started as ``python -m rosaos.devices.host`` imports pydantic, FastMCP, starlette, uvicorn
and anyio again, in pages of its own, though the kernel has imported every one of them already
(the kernel's supervisor imports the host's modules). ``rosaos up`` calls :func:`prefork` where
it forks the fork server's zygote (:mod:`rosaos.processes.zygote`): once the kernel's modules are
imported and before any thread, event loop or file. The child waits on a socket; the supervisor's
first host (:meth:`~rosaos.devices.host_process.HostProcess.spawn_batch`, the shared host in the
demo world) is this child: :meth:`HostZygote.become` hands it the host's stdin, stdout and log
file, and it runs :func:`rosaos.devices.host.main` as a spawned host would.

Seen from the supervisor nothing changes: the host is the kernel's child in a session of its own
(``killpg`` reaches it and what it spawns), it reads its job from stdin, answers on stdout, beats
its heartbeat, and exits when stdin closes (the kernel died). It is used once: a host that dies
is restarted the usual way, by ``python -m``.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import socket
import sys
import threading
from dataclasses import dataclass
from typing import IO

from rosaos.prefork import detach
from rosaos.prefork import end as end_child
from rosaos.prefork import fork_waiting as prefork_child

MESSAGE_LIMIT = 256 * 1024
"""Bytes of the one message (the environment) the zygote reads."""

_waiting: HostZygote | None = None
"""The zygote :func:`prefork` made, until the supervisor takes it (:func:`take`)."""


class ForkedHost:
    """The kernel's handle on the host a zygote became: what the supervisor uses of an
    :class:`asyncio.subprocess.Process` (``pid``, ``stdin``, ``stdout``, ``returncode``, ``wait``)."""

    def __init__(
        self, pid: int, pidfd: int, stdin: asyncio.StreamWriter, stdout: asyncio.StreamReader
    ) -> None:
        self.pid = pid
        self.stdin = stdin
        self.stdout = stdout
        self.returncode: int | None = None
        self._pidfd = pidfd
        self._exited = asyncio.get_running_loop().create_future()
        asyncio.get_running_loop().add_reader(pidfd, self._reap)

    def _reap(self) -> None:
        """The pidfd is readable: the host exited. Reap it; the code as asyncio gives it."""
        loop = asyncio.get_running_loop()
        loop.remove_reader(self._pidfd)
        os.close(self._pidfd)
        try:
            _, status = os.waitpid(self.pid, 0)
            self.returncode = os.waitstatus_to_exitcode(status)
        except ChildProcessError:  # reaped elsewhere: the code is lost, not the exit
            self.returncode = 255
        self.stdin.close()
        if not self._exited.done():
            self._exited.set_result(self.returncode)

    async def wait(self) -> int:
        """Wait for the host to exit; its return code (negative: killed by that signal)."""
        return int(await asyncio.shield(self._exited))


@dataclass
class HostZygote:
    """The kernel's side of a forked child that waits to become the first device host."""

    pid: int
    sock: socket.socket

    async def become(self, log_file: int) -> ForkedHost | None:
        """Make the zygote the host, with ``log_file`` (an open descriptor) as its stderr; its
        handle, or None (and the zygote discarded) when it is gone."""
        loop = asyncio.get_running_loop()
        stdin_read, stdin_write = os.pipe()
        stdout_read, stdout_write = os.pipe()
        theirs = [stdin_read, stdout_write, log_file]
        try:
            pidfd = os.pidfd_open(self.pid)
        except OSError:
            for fd in (*theirs[:2], stdin_write, stdout_read):
                os.close(fd)
            self.discard()
            return None
        try:
            message = json.dumps({"env": dict(os.environ)}).encode()
            socket.send_fds(self.sock, [message], theirs)
        except OSError:
            os.close(pidfd)
            for fd in (stdin_write, stdout_read):
                os.close(fd)
            self.discard()
            return None
        finally:
            for fd in theirs[:2]:  # the kernel keeps no copy: the host's EOF is the host's alone
                os.close(fd)
        self.sock.close()
        stdout = asyncio.StreamReader(loop=loop)
        await loop.connect_read_pipe(lambda: asyncio.StreamReaderProtocol(stdout), _pipe(stdout_read, "rb"))
        transport, protocol = await loop.connect_write_pipe(
            lambda: asyncio.StreamReaderProtocol(asyncio.StreamReader()), _pipe(stdin_write, "wb")
        )
        stdin = asyncio.StreamWriter(transport, protocol, None, loop)
        return ForkedHost(self.pid, pidfd, stdin, stdout)

    def discard(self) -> None:
        """Close the zygote's socket (it exits) and reap it."""
        end_child(self.pid, self.sock)


def prefork() -> HostZygote | None:
    """Fork the zygote (see the module docstring) and keep it for :func:`take`; None where forking
    would be unsafe (a thread runs) or is not possible (no ``fork``, no pidfd to watch it by)."""
    global _waiting
    if _waiting is not None:
        return _waiting
    if threading.active_count() != 1 or not hasattr(os, "fork") or not hasattr(os, "pidfd_open"):
        return None
    # What the host runs (the kernel's supervisor has imported it already; this keeps it so).
    import rosaos.devices.host
    import rosaos.devices.host_batch  # noqa: F401

    forked = prefork_child(_wait_then_host)
    if forked is None:
        return None
    _waiting = HostZygote(*forked)
    return _waiting


def take() -> HostZygote | None:
    """The zygote :func:`prefork` made, once: the supervisor's first host comes from it."""
    global _waiting
    zygote, _waiting = _waiting, None
    return zygote


def discard() -> None:
    """End the zygote if nothing took it (a world with no local device)."""
    if (zygote := take()) is not None:
        zygote.discard()


def _wait_then_host(sock: socket.socket) -> int:
    """In the child: drop the kernel's files, wait for :meth:`HostZygote.become`, then host."""
    detach(sock)  # the supervisor kills it by group; stdin, stdout and log come with the message
    try:
        message, fds, _, _ = socket.recv_fds(sock, MESSAGE_LIMIT, 3)
    except OSError:
        return 0
    if not message or len(fds) != 3:  # the kernel died or discarded it
        return 0
    sock.close()
    for target, fd in enumerate(fds):  # stdin, stdout, stderr (the host's log)
        os.dup2(fd, target)
        os.close(fd)
    sys.stdin = open(0, encoding="utf-8", closefd=False)  # noqa: SIM115 (the host's own stdin)
    request = json.loads(message)
    os.environ.clear()
    os.environ.update(request["env"])
    with contextlib.suppress(ValueError):  # as ``python -P``: the working directory shadows nothing
        sys.path.remove(os.getcwd())
    with contextlib.suppress(ValueError):
        sys.path.remove("")
    from rosaos.devices import host

    code = host.main(["rosaos.devices.host"])
    sys.stdout.flush()
    sys.stderr.flush()
    return code


def _pipe(fd: int, mode: str) -> IO[bytes]:
    """An unbuffered file over one end of a pipe, for the event loop's pipe transports."""
    return os.fdopen(fd, mode, buffering=0)
