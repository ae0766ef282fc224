"""The fallback simulation (``--mockup-sim``, no MuJoCo) and the daemon's lifecycle: no orphans."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from rosaos.drivers import DeviceError
from rosaos_reachy import daemon as daemon_module
from rosaos_reachy.daemon import SimDaemon, daemon_command

from .reachy_support import running_robot, sim_context

pytestmark = pytest.mark.slow


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


async def test_mockup_robot_sleeps_wakes_and_leaves_no_process_behind(tmp_path: Path) -> None:
    ctx = sim_context(tmp_path, physics="mockup", awake=False)
    async with running_robot(ctx) as robot:
        assert robot.backend.daemon is not None
        pid = robot.backend.daemon.process.pid
        state = await robot.call("get_state")
        assert state["mode"] == "sim: mockup" and state["awake"] is False
        assert state["antennas"] == [174.8, 174.8]  # folded down: the SDK's sleep pose
        looked = await robot.call("look", direction="left")
        assert looked["message"] == "woke up first; looking left" and looked["awake"] is True
        assert looked["head"]["yaw"] == 30.0
        asleep = await robot.call("sleep")
        assert asleep["awake"] is False and asleep["head"]["pitch"] > 15
    assert not alive(pid), "the daemon outlived the backend"


def test_the_daemon_dies_with_the_process_that_started_it(tmp_path: Path) -> None:
    script = textwrap.dedent(
        f"""
        import asyncio, sys, time
        from pathlib import Path
        from rosaos_reachy.daemon import SimDaemon

        async def main():
            daemon = await SimDaemon.start("mockup", Path({str(tmp_path)!r}), 90)
            print(daemon.process.pid, flush=True)
            await asyncio.sleep(600)

        asyncio.run(main())
        """
    )
    parent = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        assert parent.stdout is not None
        pid = int(parent.stdout.readline())
        assert alive(pid)
        parent.send_signal(signal.SIGKILL)  # no cleanup code runs: only the kernel's death signal
        parent.wait()
        deadline = time.monotonic() + 15
        while alive(pid) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not alive(pid), "the daemon was orphaned"
    finally:
        if parent.poll() is None:
            parent.kill()


async def test_mujoco_wanted_but_missing_is_refused_with_the_fix(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(daemon_module, "mujoco_available", lambda: "the mujoco package is not installed")
    with pytest.raises(DeviceError, match="physics = 'mockup'"):
        await SimDaemon.start("mujoco", tmp_path, 5)


def test_the_daemon_runs_headless_without_media_downloads_or_sleep_on_stop() -> None:
    command = daemon_command("mujoco", 8123)
    for flag in ("--sim", "--headless", "--no-media", "--no-preload-datasets", "--no-goto-sleep-on-stop"):
        assert flag in command
    assert command[command.index("--fastapi-port") + 1] == "8123"
    assert command[command.index("--fastapi-host") + 1] == "127.0.0.1"
    assert "--mockup-sim" in daemon_command("mockup", 8123)
