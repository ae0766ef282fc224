"""The fork server, ``python -m rosaos.processes.forkserver FD [--park NAME KEY] [MODULE ...]``: forks workers.

A one-off worker started as ``python -m rosaos.processes.worker`` spends seconds starting Python
and importing pydantic-ai and FastMCP. The fork server does that once: it imports the worker's
modules (and ``MODULE``s, e.g. the process model's), then forks a ready-made worker for each
request, in milliseconds. The pool's side is :mod:`rosaos.processes.forking`.

Protocol: one JSON object per message on the UNIX ``SOCK_SEQPACKET`` socket ``FD``.

- server to pool: ``{"event": "ready", "pid": P}`` once the imports are done, or
  ``{"event": "unusable", "error": ...}`` (then it exits) when forking would not be safe.
- pool to server: ``{"spawn": N}`` with two file descriptors (``SCM_RIGHTS``): the new worker's
  stdin (a pipe's read end) and stdout (a pipe's write end).
- server to pool: ``{"event": "spawned", "spawn": N, "pid": C}`` once worker ``C`` runs in its own
  session, or ``{"event": "failed", "spawn": N, "error": ...}``.
- server to pool: ``{"event": "exited", "pid": C, "returncode": R}`` when a worker ends (the server
  is its parent and reaps it); ``R`` follows asyncio's convention: negative is the killing signal.

Parking (``--park NAME KEY``, what ``rosaos up`` asks for): when the socket closes, the kernel died
(a kernel that stops kills the server first). Instead of exiting, the server waits up to
``PARK_SECONDS`` on the abstract UNIX socket ``NAME`` for the next kernel of the same data
directory. That kernel connects and sends ``{"adopt": KEY}`` with its stderr as one file
descriptor; the server answers ``{"event": "ready", "pid": P}`` and serves it from then on, so a
restart after a crash has warm workers at once instead of after seconds of imports. It refuses
(``{"event": "refused", "error": ...}``, then exits) a peer of another user, another key (the key
digests the Python, the environment, the preloaded modules and the rosaOS version: a worker forked
from it must be what a new server would fork), or when a module file it imported has changed
since. While parked its stderr is ``/dev/null``, so it holds no dead kernel's terminal or pipe.

A forked worker is what ``python -m rosaos.processes.worker`` would be: its own session and
process group, the pipes as stdin and stdout, stderr shared with the server (the kernel's, as a
spawned worker has), the same environment, Python's default signal handling, and the worker
module run as ``__main__``. The server starts no thread and no event loop, which is what makes
forking it safe. It exits when the pool closes the socket; workers still running then end on
their own when their stdin closes, as warm workers do when the kernel dies.
"""

from __future__ import annotations

import atexit
import contextlib
import gc
import importlib
import json
import os
import runpy
import select
import signal
import socket
import struct
import sys
import threading
import time
from collections.abc import Sequence
from typing import Any, NoReturn

WORKER = "rosaos.processes.worker"
PRELOAD = (WORKER, "rosaos.models.routing")
"""Imported by every fork server: the worker and what it imports for its first job."""
FIRST_JOB = ("anyio._backends._asyncio", "jsonschema", "genai_prices.data")
"""What the libraries import lazily during a worker's first job (about 50 ms; found by comparing
``sys.modules`` before and after one). Best effort, like the extra modules: a name that a newer
library version no longer has is skipped."""
MESSAGE_LIMIT = 64 * 1024
SETUP_DONE = b"+"
"""What a new worker writes to the server once it has its own session and its pipes."""
PARK_SECONDS = 60.0
"""How long a server whose kernel died waits for the next kernel to adopt it (see the docstring)."""
ADOPT_TIMEOUT = 5.0
"""Seconds a connected peer has to send its adopt request."""


def main() -> None:
    """Entry point: import the worker's modules, then serve spawn requests until the socket closes."""
    since = time.time()  # a module file changed after this makes the server unfit for adoption
    sock = socket.socket(fileno=int(sys.argv[1]))
    extra = sys.argv[2:]
    park: tuple[str, str] | None = None
    if extra[:1] == ["--park"]:
        park, extra = (extra[1], extra[2]), extra[3:]
    serve(sock, park, extra, since)


def import_worker_modules(extra: Sequence[str] = ()) -> None:
    """Import what every worker needs (and ``extra``, best effort), so that forks find it loaded."""
    for module in (*PRELOAD, *FIRST_JOB, *extra):
        # Extra modules are a best guess (a model's module): one that fails is imported, and its
        # error reported, by the worker that needs it.
        with contextlib.suppress(Exception):
            importlib.import_module(module)
    importlib.import_module(WORKER)  # not optional: raise here if the worker cannot be imported
    # Built once here, before any fork: every worker then shares the CA bundle's pages for free.
    importlib.import_module("rosaos.tls").shared_context()


def serve(sock: socket.socket, park: tuple[str, str] | None, extra: Sequence[str], since: float) -> None:
    """Import, then serve the pool on ``sock`` (and park, with ``park``) until there is none.

    ``since`` is when this process started importing: a module file changed after it makes the
    server unfit for adoption. Also what a fork server forked from the kernel runs
    (:mod:`rosaos.processes.zygote`), where most imports are done already.
    """
    import_worker_modules(extra)
    # The worker's imports stay loaded; the module itself is dropped, so that each worker runs it
    # afresh as __main__, exactly as ``python -m`` does.
    sys.modules.pop(WORKER)
    package, _, name = WORKER.rpartition(".")
    delattr(sys.modules[package], name)
    threads = [thread.name for thread in threading.enumerate() if thread is not threading.main_thread()]
    with contextlib.suppress(OSError), sock:
        if threads:
            reason = f"an imported module started threads ({', '.join(threads)}), so forking is unsafe"
            _send(sock, {"event": "unusable", "error": reason})
            return
        # Objects that exist now are never collected: forked workers share their memory pages
        # instead of each copying them when the collector walks them.
        gc.collect()
        gc.freeze()
        _serve(sock, park, since)


def _serve(sock: socket.socket, park: tuple[str, str] | None, since: float) -> None:
    wake_r, wake_w = os.pipe()
    os.set_blocking(wake_w, False)
    os.set_blocking(wake_r, False)
    # SIGCHLD needs a Python handler for the wakeup fd to be written; the loop does the reaping.
    signal.set_wakeup_fd(wake_w)
    signal.signal(signal.SIGCHLD, _ignore)
    _send(sock, {"event": "ready", "pid": os.getpid()})
    current: socket.socket | None = sock
    while current is not None:
        with contextlib.suppress(OSError), current:
            _serve_pool(current, wake_r, wake_w)
        # The pool's end closed without a kill: its kernel died. Wait for the next one, if asked to.
        current = _park(park[0], park[1], since, wake_r) if park is not None else None


def _serve_pool(sock: socket.socket, wake_r: int, wake_w: int) -> None:
    """Serve one pool until it closes its end."""
    while True:
        readable, _, _ = select.select([sock.fileno(), wake_r], [], [])
        if wake_r in readable:
            _drain(wake_r)
            _reap(sock)
        if sock.fileno() in readable:
            message, fds, _, _ = socket.recv_fds(sock, MESSAGE_LIMIT, 2)
            if not message:  # the pool closed its end
                return
            _spawn(sock, message, fds, keep_out=(wake_r, wake_w))


def _park(name: str, key: str, since: float, wake_r: int) -> socket.socket | None:
    """Wait for the next kernel to adopt this server; its socket, or None (then the server exits)."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 2)  # the dead kernel's terminal or pipe is not held open
    os.close(devnull)
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    with listener:
        try:
            listener.bind("\0" + name)  # abstract: nothing on disk to leave behind
        except OSError:  # another parked server of this data directory has the name
            return None
        listener.listen(4)
        deadline = time.monotonic() + PARK_SECONDS
        while (left := deadline - time.monotonic()) > 0:
            readable, _, _ = select.select([listener.fileno(), wake_r], [], [], left)
            if wake_r in readable:
                _drain(wake_r)
                _reap(None)  # the dead kernel's workers, ending as their stdin closed
            if listener.fileno() in readable:
                conn, _ = listener.accept()
                adopted, settled = _adopt(conn, key, since)
                if adopted:
                    return conn
                conn.close()
                if settled:  # a kernel of this data directory that cannot use this server
                    return None
    return None


def _adopt(conn: socket.socket, key: str, since: float) -> tuple[bool, bool]:
    """Answer one adopt request: (adopted, whether a kernel came that this server does not fit)."""
    peer_uid = struct.unpack("3i", conn.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, 12))[1]
    if peer_uid != os.getuid():
        return False, False
    conn.settimeout(ADOPT_TIMEOUT)
    try:
        message, fds, _, _ = socket.recv_fds(conn, MESSAGE_LIMIT, 1)
    except OSError:
        return False, False
    try:
        asked = json.loads(message).get("adopt")
    except (ValueError, AttributeError):
        asked = None
    why = "not an adopt request" if asked is None else None
    if why is None and asked != key:
        why = "its Python, environment, model modules or rosaOS version differ"
    if why is None:
        why = _changed_since(since)
    if why is not None or len(fds) != 1:
        for fd in fds:
            os.close(fd)
        with contextlib.suppress(OSError):
            _send(conn, {"event": "refused", "error": why or "no stderr was passed"})
        return False, asked is not None
    os.dup2(fds[0], 2)  # the new kernel's stderr: forked workers write their logs where it does
    os.close(fds[0])
    conn.settimeout(None)
    try:
        _send(conn, {"event": "ready", "pid": os.getpid()})
    except OSError:
        return False, False
    return True, True


def _changed_since(since: float) -> str | None:
    """The first imported module whose file changed after the server started importing, said so."""
    for module in list(sys.modules.values()):
        path = getattr(module, "__file__", None)
        if not path:
            continue
        try:
            if os.stat(path).st_mtime > since:
                return f"{path} changed since the fork server imported it"
        except OSError:
            continue
    return None


def _drain(fd: int) -> None:
    with contextlib.suppress(BlockingIOError):
        while os.read(fd, 512):
            pass


def _spawn(sock: socket.socket, message: bytes, fds: list[int], keep_out: tuple[int, ...]) -> None:
    try:
        spawn = json.loads(message)["spawn"]
    except (ValueError, KeyError, TypeError):
        spawn = None
    if spawn is None or len(fds) != 2:
        _refuse(sock, spawn, "not a spawn request with two pipes", fds)
        return
    stdin_fd, stdout_fd = fds
    try:
        setup_r, setup_w = os.pipe()
    except OSError as failure:
        _refuse(sock, spawn, f"no pipe: {failure.strerror}", fds)
        return
    sys.stdout.flush()
    sys.stderr.flush()
    try:
        pid = os.fork()
    except OSError as failure:
        _refuse(sock, spawn, f"fork failed: {failure.strerror}", [*fds, setup_r, setup_w])
        return
    if pid == 0:
        _become_worker(sock, stdin_fd, stdout_fd, setup_w, close=(*keep_out, setup_r))
    # The pipes must not leak into the next worker: its exit would then not close them.
    for fd in (setup_w, stdin_fd, stdout_fd):
        os.close(fd)
    # Reply once the worker is in its own process group, so the pool's killpg(pid) reaches it.
    with os.fdopen(setup_r, "rb", buffering=0) as setup:
        done = setup.read(1) == SETUP_DONE
    if done:
        _send(sock, {"event": "spawned", "spawn": spawn, "pid": pid})
    else:  # it died setting up; it is reaped (and its exit sent) like any other
        _send(sock, {"event": "failed", "spawn": spawn, "error": f"worker {pid} died while starting"})


def _reap(sock: socket.socket | None) -> None:
    """Reap ended workers and tell the pool (``sock``; None while parked: no one asks)."""
    while True:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        if sock is not None:
            _send(sock, {"event": "exited", "pid": pid, "returncode": os.waitstatus_to_exitcode(status)})


def _become_worker(
    sock: socket.socket, stdin_fd: int, stdout_fd: int, setup_w: int, close: tuple[int, ...]
) -> NoReturn:
    """In the forked child: turn into a worker as ``python -m rosaos.processes.worker`` starts one."""
    code = 1
    try:
        os.setsid()
        signal.set_wakeup_fd(-1)
        signal.signal(signal.SIGCHLD, signal.SIG_DFL)
        # Python's own SIGINT handling, whoever started this server: one started by a process that
        # ignored SIGINT (a job put in the background by a shell) would pass that on to every worker
        # it forks, where a spawned worker of a kernel that catches SIGINT gets Python's handler.
        signal.signal(signal.SIGINT, signal.default_int_handler)
        sock.close()
        for fd in close:
            os.close(fd)
        os.dup2(stdin_fd, 0)
        os.dup2(stdout_fd, 1)
        os.close(stdin_fd)
        os.close(stdout_fd)
        os.write(setup_w, SETUP_DONE)
        os.close(setup_w)
        # random reseeds itself after a fork (os.register_at_fork), as do logging's locks.
        code = _run_worker()
    finally:
        os._exit(code)


def _run_worker() -> int:
    """Run the worker module as ``__main__`` and end the way the interpreter would; return the exit code."""
    sys.argv = sys.argv[:1]  # run_module sets argv[0] to the worker's file, like ``python -m``
    code = 0
    interrupted = False
    try:
        runpy.run_module(WORKER, run_name="__main__", alter_sys=True)
    except SystemExit as exit_:
        if exit_.code is None:
            code = 0
        elif isinstance(exit_.code, int):
            code = exit_.code
        else:
            print(exit_.code, file=sys.stderr)
            code = 1
    except KeyboardInterrupt:
        interrupted = True
    except BaseException as error:
        sys.excepthook(type(error), error, error.__traceback__)
        code = 1
    # What interpreter shutdown does: wait for threads, run atexit, flush the standard streams.
    shutdown_threads = getattr(threading, "_shutdown", None)
    if shutdown_threads is not None:
        shutdown_threads()
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    if interrupted:  # Python ends an uncaught Ctrl-C by dying of SIGINT
        signal.signal(signal.SIGINT, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGINT)
    return code


def _refuse(sock: socket.socket, spawn: Any, error: str, fds: list[int]) -> None:
    for fd in fds:
        os.close(fd)
    _send(sock, {"event": "failed", "spawn": spawn, "error": error})


def _send(sock: socket.socket, message: dict[str, Any]) -> None:
    sock.send(json.dumps(message).encode())


def _ignore(signum: int, frame: object) -> None:
    pass


if __name__ == "__main__":
    main()
