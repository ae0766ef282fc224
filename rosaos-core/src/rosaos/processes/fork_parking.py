"""Adopting the fork server a dead kernel left: fast restarts after a crash.

A fork server started with ``--park NAME KEY`` (:mod:`rosaos.processes.forkserver`) does not exit
when its kernel dies: it waits a minute on the abstract UNIX socket ``NAME`` for the next kernel of
the same data directory. :func:`adopt_parked` is that next kernel's side. The imports a new fork
server would spend seconds of CPU on (pydantic-ai, FastMCP, the models) are already done, so the
restarted kernel's warm workers are forked at once.

A parked server is adopted only by the same user (``SO_PEERCRED``) and only when it is what a new
one would be: the same :func:`park_key` (Python, environment, preloaded modules, rosaOS version)
and no module file changed since it imported it. Otherwise it refuses, exits, and the kernel
starts a fresh one as it always did.
"""

from __future__ import annotations

import asyncio
import hashlib
import json
import logging
import os
import socket
import struct
from collections.abc import Mapping, Sequence
from pathlib import Path

log = logging.getLogger(__name__)

ADOPT_TIMEOUT = 5.0
"""Seconds to wait for a parked fork server's answer before starting a new one."""
MESSAGE_LIMIT = 64 * 1024
VOLATILE = frozenset({"PWD", "OLDPWD", "SHLVL", "_", "COLUMNS", "LINES", "PYTEST_CURRENT_TEST"})
"""Variables a shell or a test runner changes from one start to the next, which no worker reads:
left out of the key, so they alone do not keep a restart from adopting (the working directory
itself is in it)."""


def park_name(data_dir: Path) -> str:
    """The abstract socket name under which a fork server of ``data_dir`` waits for its next kernel."""
    digest = hashlib.sha256(str(data_dir.resolve()).encode()).hexdigest()[:32]
    return f"rosaos-fork-server-{digest}"


def park_key(python: str, env: Mapping[str, str], preload: Sequence[str]) -> str:
    """What a parked server must have been started with to be adopted: a worker it forks must be
    what a fresh server would fork (the same API keys in its environment, the same model modules)."""
    import rosaos

    kept = sorted((name, value) for name, value in env.items() if name not in VOLATILE)
    what = [python, os.getcwd(), kept, list(preload), rosaos.__version__]
    return hashlib.sha256(json.dumps(what).encode()).hexdigest()


async def adopt_parked(name: str, key: str) -> tuple[socket.socket, int] | None:
    """Connect to the fork server parked under ``name`` and adopt it; its socket and pid, or None
    (none is parked, or it does not fit: then it exits, and the caller starts a new one)."""
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    try:
        sock.connect("\0" + name)
        pid, uid = struct.unpack("3i", sock.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, 12))[:2]
        if uid != os.getuid():
            raise ValueError(f"it runs as user {uid}")
        # Our stderr goes with the request: the workers it forks from now on log where we do.
        socket.send_fds(sock, [json.dumps({"adopt": key}).encode()], [2])
        sock.setblocking(False)
        async with asyncio.timeout(ADOPT_TIMEOUT):
            answer = json.loads(await asyncio.get_running_loop().sock_recv(sock, MESSAGE_LIMIT))
        if answer.get("event") != "ready":
            raise ValueError(str(answer.get("error", answer)))
    except (FileNotFoundError, ConnectionRefusedError):  # none is parked: the usual start
        sock.close()
        return None
    except (OSError, TimeoutError, ValueError, AttributeError) as failure:
        sock.close()
        log.info("the fork server left by the last kernel was not adopted: %s", failure)
        return None
    log.info("adopted the fork server %d left by the last kernel", pid)
    return sock, pid
