"""Compositional understanding, eighth round (helper lang8a). A self-correction inside one utterance
("turn on the kitchen, no sorry, the bedroom light", "30, I mean 40") runs only the corrected
command: a whole new command replaces the first attempt, a fragment replaces the matching slot
(device, colour, direction, number, level). A learner's "more"/"less" + adjective ("make more
quiet", "too much loud", "less bright") steps in the meaning's direction, never the other way.
What must stay as it was: a negation is refused, a stop after a correction is still a stop, and
words after "no" that correct nothing ("no rush") leave the command alone.
"""

from __future__ import annotations

from typing import Any

import pytest

from rosaos.config import DeviceConfig
from rosaos.intents.understanding.compose.corrections import comparatives, corrected
from rosaos.intents.understanding.matching import IntentMatcher

from .intents_support import matcher_for as _matcher
from .intents_support import plan_calls as _calls

Call = tuple[str, str, dict[str, Any]]


@pytest.fixture(scope="module")
def world() -> IntentMatcher:
    return _matcher(
        {
            "kitchen_light": DeviceConfig(driver="tapo", description="Ceiling light in the kitchen"),
            "bedroom_light": DeviceConfig(driver="tapo", description="Ceiling light in the bedroom"),
            "speaker": DeviceConfig(driver="spotify", description="Music on the living room speaker"),
            "reachy": DeviceConfig(driver="reachy", description="Reachy Mini desktop robot"),
            "turtlebot": DeviceConfig(driver="ros", description="TurtleBot4 mobile robot with a dock"),
        }
    )


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("turn on the kitchen, no sorry, the bedroom light", [("bedroom_light", "turn_on", {})]),
        ("turn off the bedroom light, no, the kitchen light", [("kitchen_light", "turn_off", {})]),
        ("turn the bedroom light on, no wait, the kitchen one", [("kitchen_light", "turn_on", {})]),
        (
            "make the kitchen light green, no actually, make it blue",
            [("kitchen_light", "set_color_name", {"name": "blue"})],
        ),
        (
            "switch the bedroom light to red, no, green",
            [("bedroom_light", "set_color_name", {"name": "green"})],
        ),
        ("reachy look to the left, sorry, I mean to the right", [("reachy", "look", {"direction": "right"})]),
        (
            "turn the turtlebot ninety degrees left, uh, no, right",
            [("turtlebot", "rotate", {"degrees": -90})],
        ),
        ("set the volume to 30, I mean 40", [("speaker", "set_volume", {"volume": 40})]),
        ("put the speaker at 70, or rather 50", [("speaker", "set_volume", {"volume": 50})]),
        (
            "dim the kitchen light to 20 percent, actually 40",
            [("kitchen_light", "set_brightness", {"brightness": 40})],
        ),
        ("play jazz, sorry, play classical", [("speaker", "play", {"query": "classical"})]),
    ],
)
def test_a_self_correction_runs_only_the_corrected_command(
    world: IntentMatcher, said: str, expected: list[Call]
) -> None:
    assert _calls(world.match(said)) == expected


def test_a_correction_that_corrects_nothing_leaves_the_sentence_alone() -> None:
    assert corrected("turn on the kitchen light, no rush") == "turn on the kitchen light, no rush"
    assert corrected("turn on the kitchen light") == "turn on the kitchen light"


def test_a_stop_after_a_correction_is_still_a_stop() -> None:
    assert corrected("turn the volume to 50, no wait, stop") == "stop"


def test_a_negation_is_still_refused(world: IntentMatcher) -> None:
    result = world.match("don't turn on the kitchen light, sorry, the bedroom light")
    assert result.processes == ()


@pytest.mark.parametrize(
    ("said", "sign"),
    [
        ("the music is too much loud, make more quiet", -1),
        ("make it more quiet", -1),
        ("make the music a bit more loud", 1),
        ("less loud please", -1),
        ("make the music less quiet", 1),
        ("more soft", -1),
    ],
)
def test_more_or_less_with_a_loudness_word_steps_the_volume_its_way(
    world: IntentMatcher, said: str, sign: int
) -> None:
    [(device, tool, args)] = _calls(world.match(said))
    assert (device, tool) == ("speaker", "change_volume")
    assert args["delta"] * sign > 0


@pytest.mark.parametrize(
    ("said", "key", "sign"),
    [
        ("make the kitchen light more bright", "adjust_brightness", 1),
        ("kitchen light less bright", "adjust_brightness", -1),
        ("make the bedroom light less dark", "adjust_brightness", 1),
        ("make the kitchen light more warm", "adjust_color_temp", -1),
        ("make the kitchen light less warm", "adjust_color_temp", 1),
        ("bedroom light more cool please", "adjust_color_temp", 1),
        ("make the bedroom light less cold", "adjust_color_temp", -1),
    ],
)
def test_more_or_less_with_a_light_word_steps_the_light_its_way(
    world: IntentMatcher, said: str, key: str, sign: int
) -> None:
    [(_, tool, args)] = _calls(world.match(said))
    assert tool == key
    assert args["change"] * sign > 0


def test_comparatives_read_as_the_comparative_meant() -> None:
    assert comparatives("too much loud, make more quiet") == "too loud, make quieter"
    assert comparatives("a little less bright") == "a little dimmer"
    assert comparatives("give me more light") == "give me more light"


def test_rather_than_is_a_preference_not_a_correction() -> None:
    assert corrected("set it to warm, rather than cool") == "set it to warm, rather than cool"
