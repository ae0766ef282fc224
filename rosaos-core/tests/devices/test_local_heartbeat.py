"""A local device host's health checks, on a clock the test moves (no real check interval passes).

Every ``health_interval`` the supervisor looks for a fresh heartbeat line from each host
(:mod:`rosaos.devices.liveness`). A missed beat is only late; after ``unhealthy_after`` checks in a
row without one, a real ``get_state`` call decides, and a host that fails it is restarted. The
host here is a real process (the Tapo simulator) and its beats are its own; SIGSTOP freezes it as
a hung driver would. Only the waiting between checks is the test's, so the default interval
(5 s, three checks before the real call) costs no real time, and a busy machine cannot make a
check late.
"""

from __future__ import annotations

import json
import logging
import os
import signal
from collections.abc import AsyncIterator

import pytest
import pytest_asyncio

from rosaos.devices.run_files import run_file_path
from rosaos.devices.supervisor import DeviceSupervisor
from rosaos.testing.manual_clock import ManualClock

from .devices_support import drivers_for_tests, eventually, pid_alive, requires_tapo, world_of

# Device host processes; one event loop for the module, so one supervisor serves every test (each
# leaves its host beating and healthy, restarted or not).
pytestmark = [pytest.mark.slow, requires_tapo, pytest.mark.asyncio(loop_scope="module")]

TOKEN = "heartbeat-test-token"
INTERVAL = 5.0
"""The default check interval; a beat older than ``health_timeout`` (3 s) plus one beat (1 s) is missed."""
MISSES = 3
"""The default ``unhealthy_after``: missed checks in a row before the real call."""


@pytest_asyncio.fixture(scope="module", loop_scope="module")
async def watched(
    tmp_path_factory: pytest.TempPathFactory,
) -> AsyncIterator[tuple[DeviceSupervisor, ManualClock]]:
    """A supervisor serving one Tapo simulator, checking it on a manual clock."""
    clock = ManualClock()
    data_dir = tmp_path_factory.mktemp("heartbeat") / "data"
    world = world_of(
        drivers_for_tests(with_tapo=True), data_dir, lamp={"driver": "tapo", "sim": {"on": False}}
    )
    supervisor = DeviceSupervisor(
        world, data_dir, TOKEN, clock=clock, real_call_timeout=1.0, stop_grace=0.5, backoff_base=0.1
    )
    async with supervisor:
        yield supervisor, clock


def host_pid(supervisor: DeviceSupervisor) -> int:
    pid = json.loads(run_file_path(supervisor.data_dir).read_text())["devices"]["lamp"]["pid"]
    assert isinstance(pid, int)
    return pid


async def check(supervisor: DeviceSupervisor, clock: ManualClock, beat_first: bool) -> None:
    """Move the clock to the next check and let it run; ``beat_first``: wait for a real beat just
    before it, so the check finds a fresh one."""
    due = clock.next_wake
    assert due is not None, "the supervisor is not waiting for its next check"
    if beat_first:
        await clock.advance(due - 0.5 - clock.now())
        await eventually(lambda: supervisor.last_beat("lamp") == clock.now(), within=10)
    await clock.advance(due - clock.now())
    # Checked, and asleep until the next one (or the host is being restarted after the real call).
    await eventually(
        lambda: clock.next_wake == due + INTERVAL or supervisor.last_beat("lamp") is None, within=10
    )


async def test_a_beating_host_stays_healthy_check_after_check(
    watched: tuple[DeviceSupervisor, ManualClock],
) -> None:
    supervisor, clock = watched
    pid, restarts = host_pid(supervisor), supervisor.directory()["lamp"].restarts
    for _ in range(MISSES + 1):  # more checks than a silent host would be allowed
        await check(supervisor, clock, beat_first=True)
        assert supervisor.directory()["lamp"].status == "healthy"
    assert (host_pid(supervisor), supervisor.directory()["lamp"].restarts) == (pid, restarts)


async def test_a_host_frozen_for_fewer_checks_than_allowed_is_late_not_restarted(
    watched: tuple[DeviceSupervisor, ManualClock], caplog: pytest.LogCaptureFixture
) -> None:
    supervisor, clock = watched
    pid, restarts = host_pid(supervisor), supervisor.directory()["lamp"].restarts
    caplog.set_level(logging.INFO, logger="rosaos.devices.supervisor")
    os.kill(pid, signal.SIGSTOP)  # a driver hung for a while: no beat, no answer
    try:
        for _ in range(MISSES - 1):
            await check(supervisor, clock, beat_first=False)
            assert supervisor.directory()["lamp"].status == "healthy"  # late is not down
    finally:
        os.kill(pid, signal.SIGCONT)
    assert "lamp: no heartbeat at check 1; not down yet" in caplog.messages  # the check saw it late
    await check(supervisor, clock, beat_first=True)  # it beats again before the check that would ask
    await check(supervisor, clock, beat_first=True)
    assert supervisor.directory()["lamp"].status == "healthy"
    assert (host_pid(supervisor), supervisor.directory()["lamp"].restarts) == (pid, restarts)


async def test_a_host_that_stops_beating_is_asked_once_then_restarted(
    watched: tuple[DeviceSupervisor, ManualClock],
) -> None:
    supervisor, clock = watched
    pid, restarts = host_pid(supervisor), supervisor.directory()["lamp"].restarts
    os.kill(pid, signal.SIGSTOP)  # alive, but neither beats nor answers: a hung driver
    try:
        # A beat already in the pipe when it froze may still count for the first check.
        healthy_checks = 0
        while supervisor.directory()["lamp"].status == "healthy":
            assert healthy_checks <= MISSES, "a host silent for more checks than allowed was kept"
            await check(supervisor, clock, beat_first=False)
            healthy_checks += 1
        assert healthy_checks >= MISSES, "a host was given up before it missed the checks allowed"
        assert supervisor.directory()["lamp"].status in ("unhealthy", "restarting", "starting")
        await eventually(
            lambda: (
                supervisor.directory()["lamp"].status == "healthy"
                and supervisor.directory()["lamp"].restarts == restarts + 1
            )
        )
    finally:
        if pid_alive(pid):
            os.kill(pid, signal.SIGKILL)
    assert host_pid(supervisor) != pid
