"""A fork server forked from the kernel itself, so the two share the pages of what both import.

A fork server started as ``python -m rosaos.processes.forkserver`` imports pydantic-ai, FastMCP
and pydantic again: about 100 MiB that the kernel has imported already, in pages of its own.
``rosaos up`` calls :func:`prefork` once the kernel's modules are imported and before it starts
any thread, event loop or file: the child it forks (the "zygote") waits on a socket until the
worker pool asks it to :meth:`Zygote.become` the fork server. Until the kernel or the child
writes to a page, the kernel, the fork server and every worker forked from it map the same one
(``gc.freeze`` keeps the collector from writing to the objects that exist at the fork).

The zygote is used once: a fork server that dies is restarted the usual way
(:mod:`rosaos.processes.forking`). Nothing changes for the workers: the server forks them as it
always did, each in its own session, and they end when the kernel's pipes close. The zygote ends
when its socket closes: the kernel died or discarded it, or the pool adopted a parked server.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import socket
import sys
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from rosaos.prefork import detach
from rosaos.prefork import end as end_child
from rosaos.prefork import fork_waiting as prefork_child

MESSAGE_LIMIT = 64 * 1024
REAP_TRIES = 500
"""Times 10 ms to wait for a killed fork server to exit before leaving it unreaped."""

_waiting: Zygote | None = None
"""The zygote :func:`prefork` made, until the pool takes it (:func:`take`)."""


@dataclass
class Zygote:
    """The kernel's side of a forked child that waits to become the fork server."""

    pid: int
    sock: socket.socket

    def become(
        self, python: str, env: Mapping[str, str], preload: Sequence[str], park: tuple[str, str] | None
    ) -> socket.socket | None:
        """Ask the zygote to become the fork server for workers run by ``python`` with ``env``; its
        socket (the protocol of :mod:`rosaos.processes.forkserver` from here on). None, and the
        zygote discarded, when it cannot be that server (another Python) or is gone."""
        if os.path.realpath(python) != os.path.realpath(sys.executable):
            self.discard()
            return None
        message = {"env": dict(env), "preload": list(preload), "park": list(park) if park else None}
        try:
            self.sock.send(json.dumps(message).encode())
        except OSError:
            self.discard()
            return None
        return self.sock

    async def reap(self) -> int | None:
        """Reap the fork server it became, once killed; its exit code as asyncio gives it."""
        for _ in range(REAP_TRIES):
            try:
                done, status = os.waitpid(self.pid, os.WNOHANG)  # noqa: ASYNC222 (WNOHANG: never blocks)
            except ChildProcessError:
                return None
            if done:
                return os.waitstatus_to_exitcode(status)
            await asyncio.sleep(0.01)
        return None

    def discard(self) -> None:
        """Close the zygote's socket (it exits) and reap it."""
        end_child(self.pid, self.sock)


def prefork() -> Zygote | None:
    """Fork the zygote (see the module docstring) and keep it for :func:`take`; None where forking
    would be unsafe (a thread runs) or is not possible (no ``fork``, no ``SOCK_SEQPACKET``)."""
    global _waiting
    if _waiting is not None:
        return _waiting
    if threading.active_count() != 1 or not hasattr(os, "fork") or not Path("/proc/self/stat").exists():
        return None
    from rosaos.processes import forkserver

    forkserver.import_worker_modules()  # the kernel has most of it; the rest is shared from here on
    since = _process_start_time()
    forked = prefork_child(lambda sock: _wait_then_serve(sock, since))
    if forked is None:
        return None
    _waiting = Zygote(*forked)
    return _waiting


def take() -> Zygote | None:
    """The zygote :func:`prefork` made, once: the pool's first fork server comes from it."""
    global _waiting
    zygote, _waiting = _waiting, None
    return zygote


def _wait_then_serve(sock: socket.socket, since: float) -> int:
    """In the child: drop the kernel's files, wait for :meth:`Zygote.become`, then serve."""
    detach(sock)  # the pool kills it by group; a parked server must not hold the kernel's stdout
    message = sock.recv(MESSAGE_LIMIT)
    if not message:  # the kernel died, discarded it, or adopted a parked server instead
        return 0
    request = json.loads(message)
    os.environ.clear()
    os.environ.update(request["env"])
    # What ``python -m`` would put on sys.path from the workers' PYTHONPATH (e.g. a model's module).
    for path in reversed(request["env"].get("PYTHONPATH", "").split(os.pathsep)):
        if path and path not in sys.path:
            sys.path.insert(0, path)
    with contextlib.suppress(ValueError):  # ``python -P``: the working directory shadows nothing
        sys.path.remove(os.getcwd())
    # The two start-up settings a worker's environment may change (the tests' bytecode cache).
    sys.dont_write_bytecode = bool(os.environ.get("PYTHONDONTWRITEBYTECODE"))
    sys.pycache_prefix = os.environ.get("PYTHONPYCACHEPREFIX") or None
    from rosaos.processes import forkserver

    park = (str(request["park"][0]), str(request["park"][1])) if request["park"] else None
    forkserver.serve(sock, park, [str(module) for module in request["preload"]], since)
    return 0


def _process_start_time() -> float:
    """When this process started (epoch seconds): every module it imported was read after it."""
    ticks = os.sysconf("SC_CLK_TCK")
    started = int(Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()[19])
    for line in Path("/proc/stat").read_text().splitlines():
        if line.startswith("btime "):
            return int(line.split()[1]) + started / ticks  # btime is cut to whole seconds: earlier
    return 0.0  # unknown: any module file's time counts as a change, so it is never adopted
