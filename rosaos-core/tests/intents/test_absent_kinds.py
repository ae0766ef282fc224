"""A kind of device the world lacks, said in a room it has, is refused and names what the room
has; it never acts on another device there ("turn on the fan in the bedroom" once turned on the
bedroom's lamp). The same nouns as a place or in a remark leave the command alone."""

from __future__ import annotations

import pytest

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.vocabulary import sources_from_config
from rosaos.intents.understanding.absent_kinds import AbsentKinds
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.plugins import load_drivers

from .intents_support import plan_calls


@pytest.fixture(scope="module")
def flat() -> IntentMatcher:
    devices = {
        "bedside": DeviceConfig(driver="tapo", description="Bedside lamp in the bedroom"),
        "kitchen_light": DeviceConfig(driver="tapo", description="Ceiling light in the kitchen"),
        "porch_light": DeviceConfig(driver="tapo", description="Light by the front door"),
        "spotify": DeviceConfig(driver="spotify", description="Music on the living room speaker"),
        "turtlebot": DeviceConfig(driver="ros", description="TurtleBot4 robot with a camera"),
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


@pytest.mark.parametrize(
    ("said", "kind", "there"),
    [
        ("turn on the fan in the bedroom", "fan", "bedside"),
        ("switch the kitchen heater on", "heater", "kitchen light"),
        ("put the telly on in the bedroom", "telly", "bedside"),
        ("could you open the blinds in the kitchen", "blinds", "kitchen light"),
        ("turn the bedroom air conditioner off", "air conditioner", "bedside"),
        ("start the dishwasher in the kitchen", "dishwasher", "kitchen light"),
    ],
)
def test_a_kind_the_world_lacks_is_refused_naming_the_rooms_devices(
    flat: IntentMatcher, said: str, kind: str, there: str
) -> None:
    result = flat.match(said)
    assert not result.is_exact and result.refusal and not result.processes
    assert f"no {kind}" in result.reply and there in result.reply


def test_without_a_room_the_refusal_lists_every_device(flat: IntentMatcher) -> None:
    result = flat.match("boil the kettle")
    assert result.refusal and not result.processes
    assert "no kettle" in result.reply and "spotify" in result.reply


@pytest.mark.parametrize(
    ("said", "device", "tool"),
    [
        (
            "turn on the light by the door",
            "porch_light",
            "turn_on",
        ),  # the door is a place, and a word of its description
        ("turn on the light in the bedroom", "bedside", "turn_on"),
        ("turn off the kitchen light, the tv is too loud", "kitchen_light", "turn_off"),
        ("dim the bedside lamp, we're watching the tv", "bedside", "adjust_brightness"),
        ("play some jazz, I'm a big fan", "spotify", "play"),
    ],
)
def test_kind_nouns_as_places_or_remarks_leave_the_command(
    flat: IntentMatcher, said: str, device: str, tool: str
) -> None:
    result = flat.match(said)
    assert result.is_exact, result.reply
    assert [(name, called) for name, called, _ in plan_calls(result)] == [(device, tool)]


def test_a_kind_the_world_has_is_not_refused(flat: IntentMatcher) -> None:
    """The turtlebot's description says camera: "the camera" is no absent kind here."""
    kinds = AbsentKinds(flat.context)
    assert kinds.refusal("turn the camera on") is None
    assert kinds.refusal("turn the fans on") is not None
