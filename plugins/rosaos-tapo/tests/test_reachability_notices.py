"""Tapo notices: a bulb that stops answering is ``unreachable`` once, and ``reachable`` when back."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from rosaos.drivers import DeviceContext, DeviceError, NoticeBoard
from rosaos_tapo.plugin import SPEC, sim_backend
from rosaos_tapo.settings import TapoSettings


async def test_a_bulb_that_goes_away_and_comes_back_is_two_notices(tmp_path: Path, monkeypatch: Any) -> None:
    board = NoticeBoard("lamp", "tapo", SPEC.notices)
    ctx = DeviceContext("lamp", "Lamp", TapoSettings(), "sim", {}, tmp_path, notices=board)
    backend = sim_backend(ctx)
    await backend.start()
    try:
        await backend.state()

        async def unplugged() -> None:  # the physical edge: the bulb does not answer
            raise TimeoutError

        monkeypatch.setattr(backend.device, "update", unplugged)
        for _ in range(2):
            with pytest.raises(DeviceError, match="cannot reach"):
                await backend.state()
        monkeypatch.undo()
        await backend.turn_on()
    finally:
        await backend.close()
    notices = board.after(0).notices
    assert [n.name for n in notices] == ["unreachable", "reachable"]
    assert notices[0].importance == "notify" and "cannot reach" in notices[0].data["error"]
    assert notices[1].message == "lamp answers again"
