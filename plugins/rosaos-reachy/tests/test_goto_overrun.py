"""A goto the daemon failed at its very end, on a busy computer, still reaches its target.

reachy-mini 1.12's daemon checks its clock against the move's duration, then reads it again to
interpolate; descheduled between the two reads, it fails the move with "time value is out of
range [0,1]" (seen as ``rotate_body: time value is out of range [0,1]`` in the MuJoCo tests under
load). The daemon's scheduling cannot be provoked from a test, so the SDK client here is a
stand-in that fails the way the daemon does; everything above it is the driver's own code.
"""

from __future__ import annotations

import threading
from typing import Any
from uuid import UUID, uuid4

import pytest

from rosaos_reachy.robot import GOTO_ATTEMPTS, NEUTRAL_POSTURE, RobotLink

OVERRUN = "Task failed with error: time value is out of range [0,1]"


class DaemonClient:
    """Records what the driver sends; each goto fails with the next error in ``failures``."""

    def __init__(self, failures: list[str | None], on_failure: Any = None) -> None:
        self.failures = failures
        self.on_failure = on_failure
        self.sent: list[Any] = []
        self.stops = 0

    def send_task_request(self, request: Any) -> UUID:
        self.sent.append(request)
        return uuid4()

    def wait_for_task_completion(self, task: UUID, timeout: float) -> None:
        error = self.failures.pop(0) if self.failures else None
        if error is not None:
            if self.on_failure is not None:
                self.on_failure()
            raise Exception(error)

    def send_command(self, command: Any) -> None:
        self.stops += 1


class Mini:
    def __init__(self, client: DaemonClient) -> None:
        self.client = client


def link_to(client: DaemonClient) -> RobotLink:
    link = RobotLink("localhost", 8000, media=False, timeout=1.0)
    link.mini = Mini(client)  # type: ignore[assignment]
    return link


TARGET = NEUTRAL_POSTURE.with_head(yaw=30.0)


def test_a_goto_the_daemon_overran_is_sent_again_and_returns_on_arrival() -> None:
    client = DaemonClient([OVERRUN])
    link_to(client).goto(TARGET, 0.5)
    assert len(client.sent) == 2
    assert client.sent[1] == client.sent[0], "the same target, from wherever the head is now"
    assert client.sent[0].duration == 0.5 and client.sent[0].body_yaw == 0.0


def test_a_goto_stopped_while_it_overran_is_not_sent_again() -> None:
    cancel = threading.Event()
    client = DaemonClient([OVERRUN], on_failure=cancel.set)
    link_to(client).goto(TARGET, 0.5, cancel=cancel)
    assert len(client.sent) == 1, "a stop that came in meanwhile wins: the robot stays stopped"


def test_a_cancelled_goto_is_never_sent() -> None:
    cancel = threading.Event()
    cancel.set()
    client = DaemonClient([])
    link_to(client).goto(TARGET, 0.5, cancel=cancel)
    assert client.sent == []


def test_any_other_daemon_error_is_raised_at_once() -> None:
    client = DaemonClient(["Task failed with error: motors are off"])
    with pytest.raises(Exception, match="motors are off"):
        link_to(client).goto(TARGET, 0.5)
    assert len(client.sent) == 1


def test_a_daemon_that_keeps_overrunning_fails_the_move_after_a_few_tries() -> None:
    client = DaemonClient([OVERRUN] * (GOTO_ATTEMPTS + 1))
    with pytest.raises(Exception, match="out of range"):
        link_to(client).goto(TARGET, 0.5)
    assert len(client.sent) == GOTO_ATTEMPTS


def test_a_head_only_goto_leaves_the_body_where_it_is() -> None:
    client = DaemonClient([])
    link_to(client).goto(TARGET, 0.8, body=False)
    assert client.sent[0].body_yaw is None and client.sent[0].duration == 0.8
