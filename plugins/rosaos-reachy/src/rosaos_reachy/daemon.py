"""The SDK's own daemon in simulation, run by the ``sim`` backend as a child process.

``reachy-mini-daemon --sim --headless --no-media`` simulates the robot in MuJoCo;
``--mockup-sim`` (no physics: poses are reached exactly) is the fallback where MuJoCo cannot
run. The driver then talks to it with the same SDK client as to a real robot.

No orphans: the daemon gets its own process group (so closing kills it and anything it spawned),
a parent-death signal (Linux), and the SDK's own health-check watchdog: it exits by itself when
the driver stops pinging it.
"""

from __future__ import annotations

import asyncio
import contextlib
import ctypes
import importlib.util
import logging
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import httpx

from rosaos.drivers import DeviceError
from rosaos_reachy.sim_daemon import SCENE, default_model_cache

log = logging.getLogger(__name__)

SimMode = Literal["mujoco", "mockup"]
HEALTH_TIMEOUT_S = 30.0
"""The daemon stops itself after this long without a health-check ping (the parent is gone)."""
HEALTH_PING_S = 5.0
STOP_GRACE_S = 5.0
_PR_SET_PDEATHSIG = 1


def mujoco_available() -> str | None:
    """None when MuJoCo can run here; otherwise why not (shown in ``get_state``)."""
    if importlib.util.find_spec("mujoco") is None:
        return "the mujoco package is not installed (pip install 'reachy-mini[mujoco]')"
    return None


def free_port() -> int:
    """A TCP port free on loopback right now (the daemon binds it a moment later)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def _die_with_parent() -> None:  # runs in the child between fork and exec
    with contextlib.suppress(Exception):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)


def daemon_command(mode: SimMode, port: int, model_cache: Path | None = None) -> list[str]:
    """The ``reachy-mini-daemon`` command line for ``mode`` on ``port``.

    With ``model_cache``, MuJoCo runs through :mod:`rosaos_reachy.sim_daemon`, which loads the
    scene pre-compiled from there (the same model, 160 MiB lighter at idle).
    """
    script = Path(sys.executable).with_name("reachy-mini-daemon")
    program = (
        [str(script)] if script.exists() else [shutil.which("reachy-mini-daemon") or "reachy-mini-daemon"]
    )
    if mode == "mujoco" and model_cache is not None:
        program = [sys.executable, "-m", "rosaos_reachy.sim_daemon", "--model-cache", str(model_cache), "--"]
    sim = ["--sim", "--headless", "--scene", SCENE] if mode == "mujoco" else ["--mockup-sim"]
    return [
        *program,
        *sim,
        "--no-media",  # no camera, speaker or WebRTC in simulation: the driver fakes what it needs
        "--fastapi-host", "127.0.0.1",
        "--fastapi-port", str(port),
        "--no-wake-up-on-start",  # the backend moves to the configured initial state itself
        "--no-goto-sleep-on-stop",  # a simulator has nothing to protect: stop at once
        "--no-preload-datasets",  # never download at run time
        "--dataset-update-interval", "0",
        "--timeout-health-check", str(HEALTH_TIMEOUT_S),
        "--log-level", "WARNING",
    ]  # fmt: skip


@dataclass
class SimDaemon:
    """A running simulated daemon: its mode, address and process."""

    mode: SimMode
    port: int
    process: subprocess.Popen[bytes]
    log_file: Path
    fallback_reason: str | None = None
    """Why MuJoCo is not used, when ``mode`` is ``mockup`` although MuJoCo was wanted."""
    _pinger: asyncio.Task[None] | None = None

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    @classmethod
    async def start(
        cls,
        wanted: Literal["auto", "mujoco", "mockup"],
        log_dir: Path,
        timeout: float,
        model_cache: Path | None = None,
    ) -> SimDaemon:
        """Start the daemon (MuJoCo first unless ``mockup`` is wanted) and wait until it runs.

        ``model_cache`` keeps the compiled MuJoCo scene between starts (default: the user's cache
        directory, shared by every data directory: the file is 80 MB).
        """
        reason = mujoco_available()
        if wanted == "mujoco" and reason:
            raise DeviceError(f"sim physics 'mujoco' cannot run: {reason}; or set sim physics = 'mockup'")
        auto: list[SimMode] = ["mockup"] if reason else ["mujoco", "mockup"]
        modes: list[SimMode] = auto if wanted == "auto" else [wanted]
        failures: list[str] = []
        for mode in modes:
            daemon = cls._spawn(mode, log_dir, model_cache or default_model_cache())
            try:
                await daemon._wait_running(timeout)
            except DeviceError as error:
                await daemon.stop()
                failures.append(f"{mode}: {error}")
                continue
            if mode == "mockup" and wanted == "auto":
                daemon.fallback_reason = reason or "; ".join(failures)
            daemon._pinger = asyncio.create_task(daemon._ping_forever())
            return daemon
        raise DeviceError("the simulated Reachy Mini daemon did not start: " + " | ".join(failures))

    @classmethod
    def _spawn(cls, mode: SimMode, log_dir: Path, model_cache: Path) -> SimDaemon:
        log_dir.mkdir(parents=True, exist_ok=True)
        port = free_port()
        log_file = log_dir / f"daemon-{mode}.log"
        env = dict(os.environ, HF_HUB_OFFLINE="1", PYTHONUNBUFFERED="1")  # no hub downloads, ever
        with log_file.open("wb") as out:
            process = subprocess.Popen(
                daemon_command(mode, port, model_cache),
                stdin=subprocess.DEVNULL,
                stdout=out,
                stderr=subprocess.STDOUT,
                cwd=log_dir,  # the daemon writes nothing we want in the caller's directory
                env=env,
                start_new_session=True,  # own process group: stop() kills the whole tree
                preexec_fn=_die_with_parent if sys.platform == "linux" else None,
            )
        return cls(mode=mode, port=port, process=process, log_file=log_file)

    async def _wait_running(self, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        async with httpx.AsyncClient(timeout=2.0) as http:
            while time.monotonic() < deadline:
                if self.process.poll() is not None:
                    raise DeviceError(f"exited with code {self.process.returncode}; {self._log_tail()}")
                with contextlib.suppress(httpx.HTTPError, ValueError):
                    # Ping while waiting too: the watchdog runs from the start, however slow it is.
                    await http.post(f"{self.url}/health-check")
                    status = (await http.get(f"{self.url}/api/daemon/status")).json()
                    if status.get("state") == "running":
                        return
                    if status.get("state") == "error":
                        raise DeviceError(f"daemon error: {status.get('error')}; {self._log_tail()}")
                await asyncio.sleep(0.2)
        raise DeviceError(f"not running after {timeout:g} s; {self._log_tail()}")

    async def _ping_forever(self) -> None:
        async with httpx.AsyncClient(timeout=2.0) as http:
            while self.process.poll() is None:
                with contextlib.suppress(httpx.HTTPError):
                    await http.post(f"{self.url}/health-check")
                await asyncio.sleep(HEALTH_PING_S)

    def _log_tail(self, lines: int = 6) -> str:
        try:
            text = self.log_file.read_text(errors="replace").strip().splitlines()[-lines:]
        except OSError:
            return f"see {self.log_file}"
        return f"see {self.log_file}: " + " / ".join(text)

    async def stop(self) -> None:
        """Terminate the daemon's process group; kill it if it does not exit within a few seconds."""
        if self._pinger is not None:
            self._pinger.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._pinger
        if self.process.poll() is not None:
            return
        self._signal(signal.SIGTERM)
        try:
            await asyncio.wait_for(asyncio.to_thread(self.process.wait), STOP_GRACE_S)
        except TimeoutError:
            log.warning("reachy sim daemon did not stop within %.0f s; killing it", STOP_GRACE_S)
            self._signal(signal.SIGKILL)
            await asyncio.to_thread(self.process.wait)

    def _signal(self, signum: int) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.process.pid, signum)
