"""What the offline engine sees of a world: every instance that can be served, and no placeholder."""

from __future__ import annotations

from pathlib import Path

from rosaos.intents.grammar.vocabulary import device_vocabularies
from rosaos.intents.understanding.matching import IntentMatcher

from .devices_support import drivers_for_tests, world_of


def test_a_placeholder_instance_is_not_offered_by_the_offline_engine(data_dir: Path) -> None:
    world = world_of(drivers_for_tests(), data_dir, lamp={"driver": "tiny"}, robot={"driver": "someday"})
    assert [source.name for source in device_vocabularies(world)] == ["lamp"]
    reply = IntentMatcher(device_vocabularies(world), "en").match("tell the robot to fly").reply
    assert "lamp" in reply
    assert "robot" not in reply.split("control:", 1)[1]
