"""A speed that is not a number, infinite, or vanishingly small is refused, never turned into a move.

``speed: 1e-9`` used to be accepted: a 0.5 m move then had a timeout of about 1e9 s and its call
never returned. Numbers are sent as raw JSON (NaN and Infinity literals), as a careless client
can send them; an MCP client would quietly turn them into ``null``.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path

import pytest

from rosaos.testing.device_runner import (
    RunningDevice,
    build_instance,
    load_all_drivers,
    raw_tool_call,
    run_device,
)


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningDevice]:
    instance = build_instance(load_all_drivers().get("ros"), "bot", sim={"docked": False})
    with run_device(instance, Path(tmp_path_factory.mktemp("odd-speeds"))) as device:
        yield device


@pytest.mark.parametrize("speed", [math.nan, math.inf, -math.inf, 0.0, 1e-9])
@pytest.mark.parametrize(
    ("tool", "amount"), [("move_distance", {"meters": 0.5}), ("rotate", {"degrees": 10})]
)
async def test_an_odd_speed_is_refused_naming_speed(
    robot: RunningDevice, tool: str, amount: dict[str, float], speed: float
) -> None:
    result = await raw_tool_call(robot, tool, {**amount, "speed": speed}, timeout=10)
    text = " ".join(str(block.get("text", "")) for block in result["content"])
    assert result["isError"], f"{tool}(speed={speed}) was accepted: {text}"
    assert "speed" in text
