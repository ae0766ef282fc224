"""The driver as rosaOS sees it: entry point, spec, settings, demo instances, safe stop."""

from __future__ import annotations

from typing import Any

import pytest
from pydantic import ValidationError

from rosaos.plugins import load_drivers
from rosaos_tapo.plugin import SPEC, leave_light_as_is
from rosaos_tapo.settings import TapoSettings


def test_entry_point_registers_the_tapo_driver() -> None:
    registry = load_drivers(allow={"tapo"})
    assert registry.broken == []
    info = registry.get("tapo")
    assert (info.package, info.spec.name) == ("rosaos-tapo", "tapo")


def test_a_bulb_is_held_by_one_process_at_a_time() -> None:
    assert SPEC.concurrency == "exclusive"


def test_demo_world_has_the_kitchen_light_and_living_room_lamp() -> None:
    demo = SPEC.demo_instances()
    assert demo["kitchen_light"].description == "Ceiling light in the kitchen"
    assert demo["kitchen_light"].sim == {"on": False}
    assert demo["living_room_lamp"].description == "Floor lamp in the living room"
    assert demo["living_room_lamp"].sim == {"on": True, "brightness": 60, "color_temp": 2700}


def test_settings_reject_unknown_keys() -> None:
    with pytest.raises(ValidationError, match="hots"):
        TapoSettings.model_validate({"hots": "192.168.1.50"})


def test_settings_never_show_the_password() -> None:
    settings = TapoSettings(host="192.168.1.50", username="me@example.com", password="hunter2")
    assert "hunter2" not in repr(settings)
    assert "hunter2" not in settings.model_dump_json()


async def test_safe_stop_leaves_the_light_as_it_is(open_bulb: Any) -> None:
    async with open_bulb(on=True, brightness=40) as bulb:
        before = await bulb.call("get_state")
        await leave_light_as_is(bulb.backend)
        after = await bulb.call("get_state")
    assert after == before
