"""The driver's declaration, and the settings and sim table it accepts."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rosaos.drivers import DeviceContext, DeviceError
from rosaos_reachy.plugin import SPEC, real_backend, sim_backend
from rosaos_reachy.settings import ReachySettings


def test_the_reachy_is_the_always_attached_shared_user_interface() -> None:
    assert SPEC.name == "reachy" and SPEC.implemented
    assert SPEC.always_attached is True and SPEC.concurrency == "shared"
    assert set(SPEC.backends) == {"sim", "real"}


@pytest.mark.parametrize(
    ("task", "attached"),
    [
        ("Turn on the kitchen light.", False),
        ("Undock, then search the environment for a person and report whether you found one.", False),
        ("Play some jazz.", False),
        ("Say: the battery is low", True),
        ("Tell the user the weather", True),
        ("Greet whoever comes in", True),
        ("Ask the person their name", True),
    ],
)
def test_the_reachy_joins_unasked_only_a_task_that_speaks(task: str, attached: bool) -> None:
    # Issue 22: a light switch's process does not carry the speaking tools its report needs not.
    assert SPEC.attached_pattern is not None
    assert (re.search(SPEC.attached_pattern, task, re.IGNORECASE) is not None) is attached


def test_an_unknown_sim_key_is_refused_with_the_keys_there_are(tmp_path: Path) -> None:
    ctx = DeviceContext("reachy", "robot", ReachySettings(), "sim", {"speed": 3}, tmp_path)
    with pytest.raises(DeviceError, match=r"\[devices.reachy.sim\] speed.*keys: head, antennas"):
        sim_backend(ctx)


def test_an_unknown_head_key_is_refused(tmp_path: Path) -> None:
    ctx = DeviceContext("reachy", "robot", ReachySettings(), "sim", {"head": {"tilt": 3}}, tmp_path)
    with pytest.raises(DeviceError, match="unknown keys"):
        sim_backend(ctx)


async def test_the_real_backend_says_how_to_reach_a_robot_that_is_not_there(tmp_path: Path) -> None:
    settings = ReachySettings(host="127.0.0.1", daemon_port=9, connect_timeout=1)
    backend = real_backend(DeviceContext("reachy", "robot", settings, "real", {}, tmp_path))
    with pytest.raises(
        DeviceError, match=r"cannot reach the Reachy Mini daemon at 127.0.0.1:9.*reachy-mini-daemon"
    ):
        await backend.start()
    await backend.close()
