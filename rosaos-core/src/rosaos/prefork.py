"""Forking a waiting child from the kernel, so the child shares the pages of what both import.

Both zygotes use it: the fork server's (:mod:`rosaos.processes.zygote`) and the first device
host's (:mod:`rosaos.devices.host_zygote`). ``rosaos up`` forks them once the kernel's modules are
imported and before any thread, event loop or file exists; each child then waits on a socket for
what it is to become. Until a process writes to a page, the kernel and the child map the same one.
"""

from __future__ import annotations

import contextlib
import gc
import os
import socket
import sys
from collections.abc import Callable


def fork_waiting(run: Callable[[socket.socket], int]) -> tuple[int, socket.socket] | None:
    """Fork a child that calls ``run`` with its end of a socket pair and exits with what ``run``
    returns; the child's pid and the parent's end, or None without ``SOCK_SEQPACKET``.

    ``gc.freeze`` first: the kernel's collector must not write to the objects the two share."""
    try:
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    except OSError:
        return None
    gc.collect()
    gc.freeze()
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:
        ours.close()
        code = 1
        try:
            code = run(theirs)
        finally:
            os._exit(code)
    theirs.close()
    return pid, ours


def detach(sock: socket.socket) -> None:
    """In the child: a session and group of its own (as ``start_new_session``: its owner ends it by
    group), stdin and stdout on ``/dev/null`` (a waiting child must not hold the kernel's stdout
    open), and every other file of the kernel closed but ``sock``."""
    os.setsid()
    devnull = os.open(os.devnull, os.O_RDWR)
    os.dup2(devnull, 0)
    os.dup2(devnull, 1)
    os.close(devnull)
    os.closerange(3, sock.fileno())
    os.closerange(sock.fileno() + 1, _max_fd())


def end(pid: int, sock: socket.socket) -> None:
    """Close the parent's end of a waiting child's socket (the child exits) and reap it."""
    sock.close()
    with contextlib.suppress(ChildProcessError):
        os.waitpid(pid, 0)


def _max_fd() -> int:
    with contextlib.suppress(OSError, ValueError):
        return int(os.sysconf("SC_OPEN_MAX"))
    return 1024
