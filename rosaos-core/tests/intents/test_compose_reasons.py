"""Compositional understanding, second round: kinds of language a new writer used that the reader
did not yet read. A command with its reason after it; music transport (resume, replay, repeat,
back a track); reversing with units; a robot facing front or looking straight ahead again; two
lights trading states; questions about what plays. Stops and questions name devices with the
reader's own resolver (one for every reader). Each kind is checked on several sentences, and
against what must stay refused (a negation, a device the world lacks).
"""

from __future__ import annotations

from typing import Any

import pytest

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.compose.speech import clauses, normalise, remark, without_reason
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.intents.understanding.questions import Question, read_question
from rosaos.intents.understanding.stop_words import DeviceRefs, StopRequest, read_stop

from .intents_support import home_world
from .intents_support import matcher_for as _matcher
from .intents_support import plan_calls as _calls


@pytest.fixture(scope="module")
def home() -> IntentMatcher:
    return _matcher(
        {
            "kitchen_light": DeviceConfig(driver="tapo", description="Ceiling light in the kitchen"),
            "hall_light": DeviceConfig(driver="tapo", description="Ceiling light in the hallway"),
            "bedroom_lamp": DeviceConfig(driver="tapo", description="Bedside lamp in the bedroom"),
            "desk_lamp": DeviceConfig(driver="tapo", description="Reading lamp on the work table"),
            "spotify": DeviceConfig(driver="spotify", description="Music on the living room speaker"),
        }
    )


@pytest.fixture(scope="module")
def pair() -> IntentMatcher:
    return _matcher(
        {
            "porch_light": DeviceConfig(driver="tapo", description="Light over the front porch"),
            "sofa_lamp": DeviceConfig(driver="tapo", description="Floor lamp next to the sofa"),
        }
    )


@pytest.fixture(scope="module")
def robots() -> IntentMatcher:
    return _matcher(
        {
            "turtlebot": DeviceConfig(
                driver="ros", description="TurtleBot4 mobile robot with a charging dock"
            ),
            "dog": DeviceConfig(driver="ros", description="Hiwonder PuppyPi quadruped robot dog"),
            "reachy": DeviceConfig(driver="reachy", description="Reachy Mini desktop robot"),
        }
    )


@pytest.mark.parametrize(
    ("said", "command"),
    [
        ("dim it because it's late", "dim it"),
        ("put the lamp on so I can read", "put the lamp on"),
        ("pick the music back up where it left off", "pick the music back up"),
        ("turn the music off since the kids are asleep", "turn the music off"),
        ("set it as warm as it goes", "set it as warm as it goes"),  # "as it goes" is no reason
    ],
)
def test_a_reason_after_the_command_is_cut_off(said: str, command: str) -> None:
    assert without_reason(said) == command


@pytest.mark.parametrize(
    "said",
    ["the baby is napping", "I'm trying to fall asleep", "we have guests", "my head hurts",
     "someone's at the door", "everyone's home", "this is my jam", "thank you so much"],
)  # fmt: skip
def test_statements_are_remarks(said: str) -> None:
    assert remark(normalise(said))


@pytest.mark.parametrize(
    "said", ["turn off the hall light", "kitchen light on", "the kitchen lights off", "dim the lamp"]
)
def test_commands_are_not_remarks(said: str) -> None:
    assert not remark(normalise(said))


def test_a_second_sentence_is_a_second_clause() -> None:
    assert clauses(normalise("Turn the bedroom lamp off? I'm done reading.")) == [
        "turn the bedroom lamp off",
        "i'm done reading",
    ]


@pytest.mark.parametrize(
    ("said", "calls"),
    [
        ("dim the hall light, I'm trying to fall asleep", [("hall_light", "adjust_brightness", {"change": -25})]),
        ("turn off the hall light, the baby is napping", [("hall_light", "turn_off", {})]),
        ("kill the hall light, I'm heading out", [("hall_light", "turn_off", {})]),
        ("switch on the kitchen light since I'm cooking", [("kitchen_light", "turn_on", {})]),
        ("Turn the music down a bit, we have guests", [("spotify", "change_volume", {"delta": -10})]),
        ("lower the volume, my head hurts", [("spotify", "change_volume", {"delta": -15})]),
        ("pause the music, someone's at the door", [("spotify", "pause", {})]),
        ("turn on the hall light, thank you so much", [("hall_light", "turn_on", {})]),
        ("can you turn the bedroom lamp off? I'm done reading", [("bedroom_lamp", "turn_off", {})]),
    ],
)  # fmt: skip
def test_the_reason_is_dropped_and_the_command_runs(
    said: str, calls: list[tuple[str, str, dict[str, Any]]], home: IntentMatcher
) -> None:
    result = home.match(said)
    assert result.is_exact, result.reply
    assert _calls(result) == calls


@pytest.mark.parametrize(
    "said",
    ["turn the kitchen light and the garage light on, I'm cooking",  # a device the world lacks
     "don't turn off the hall light, the baby is awake"],  # a negation
)  # fmt: skip
def test_a_reason_does_not_make_a_refusal_run(said: str, home: IntentMatcher) -> None:
    assert not home.match(said).is_exact


@pytest.mark.parametrize(
    ("said", "tool", "args"),
    [
        ("resume the music", "resume", {}),
        ("unpause please", "resume", {}),
        ("pick the music back up where it left off", "resume", {}),
        ("start the song again", "resume", {}),
        ("play it again", "resume", {}),
        ("play that song one more time", "resume", {}),
        ("hit play", "resume", {}),
        ("hit pause", "pause", {}),
        ("loop this track", "set_repeat", {"repeat": "track"}),
        ("put it on repeat", "set_repeat", {"repeat": "track"}),
        ("turn off repeat", "set_repeat", {"repeat": "off"}),
        ("I don't like this one, skip it", "next_track", {}),
        ("I don't really like this song, next one please", "next_track", {}),
        ("skip ahead", "next_track", {}),
        ("go back a track", "previous_track", {}),
        ("replay the last song", "previous_track", {}),
    ],
)
def test_music_transport(said: str, tool: str, args: dict[str, Any], home: IntentMatcher) -> None:
    result = home.match(said)
    assert result.is_exact, result.reply
    assert _calls(result) == [("spotify", tool, args)]


def test_a_song_named_like_a_pronoun_is_still_searched(home: IntentMatcher) -> None:
    assert _calls(home.match("play the beatles")) == [("spotify", "play", {"query": "the beatles"})]


@pytest.mark.parametrize(
    "said",
    ["swap the lights", "turn the on one off and the off one on", "swap them around please",
     "turn the off one on and the on one off"],
)  # fmt: skip
def test_two_lights_trade_states_by_each_toggling(said: str, pair: IntentMatcher) -> None:
    result = pair.match(said)
    assert result.is_exact, result.reply
    assert _calls(result) == [("porch_light", "toggle", {}), ("sofa_lamp", "toggle", {})]


def test_swapping_names_the_two_or_asks_which(home: IntentMatcher) -> None:
    named = home.match("switch the bedroom lamp and the desk lamp around")
    assert _calls(named) == [("bedroom_lamp", "toggle", {}), ("desk_lamp", "toggle", {})]
    many = home.match("swap the lights")
    assert many.kind == "clarify" and not many.processes


@pytest.mark.parametrize(
    ("said", "metres"),
    [
        ("back the dog up 30 cm", -0.3),
        ("back up the dog 20 centimeters", -0.2),
        ("reverse the dog one metre", -1),
        ("dog, go backwards 0.4 m", -0.4),
        ("back the dog up a bit, it's too close to the stairs", -0.3),
        ("move the dog back", -0.5),
    ],
)
def test_reversing_with_units(said: str, metres: float, robots: IntentMatcher) -> None:
    result = robots.match(said)
    assert result.is_exact, result.reply
    assert _calls(result) == [("dog", "move_distance", {"meters": metres})]


@pytest.mark.parametrize(
    ("said", "tool", "args"),
    [
        ("Reachy, look straight ahead again", "look", {"direction": "front"}),
        ("reset reachy's head", "look", {"direction": "front"}),
        ("turn reachy's head to the front", "look", {"direction": "front"}),
        ("spin reachy's body back to the front", "rotate_body", {"degrees": 0}),
        ("rotate reachy's body 45 degrees to the right", "rotate_body", {"degrees": -45}),
    ],
)
def test_the_reachy_faces_and_looks_front(
    said: str, tool: str, args: dict[str, Any], robots: IntentMatcher
) -> None:
    result = robots.match(said)
    assert result.is_exact, result.reply
    assert _calls(result) == [("reachy", tool, args)]


def test_facing_front_is_only_for_a_driver_that_declares_it(robots: IntentMatcher) -> None:
    assert not any(step[0] == "reachy" for step in _calls(robots.match("turn the turtlebot to face forward")))


@pytest.mark.parametrize(
    "said", ["what am I listening to?", "who's this by?", "what song is this", "which artist is this"]
)
def test_questions_about_what_plays(said: str) -> None:
    assert read_question(said, DeviceRefs(home_world())) == Question("playing", ())


STAIRS = [
    DeviceVocabulary(name="stair_light", driver="tapo", description="Pendant light above the stairwell"),
    DeviceVocabulary(name="hall_light", driver="tapo", description="Ceiling light in the hallway"),
    DeviceVocabulary(name="turtlebot", driver="ros", description="TurtleBot4 wheeled robot with a dock"),
    DeviceVocabulary(name="spotify", driver="spotify", description="Music on the living room speaker"),
]


@pytest.mark.parametrize(
    ("said", "devices"),
    [
        ("stop the light over the stairs", ("stair_light",)),
        ("stop the speaker", ("spotify",)),
        ("hold it, wheeled robot", ("turtlebot",)),
    ],
)
def test_a_stop_names_devices_the_way_a_command_does(said: str, devices: tuple[str, ...]) -> None:
    assert read_stop(said, DeviceRefs(STAIRS)) == StopRequest(devices)


@pytest.mark.parametrize(
    ("said", "question"),
    [
        ("is the light over the stairs on?", Question("on", ("stair_light",))),
        ("what's playing on the speaker?", Question("playing", ("spotify",))),
        ("is the wheeled robot docked?", Question("docked", ("turtlebot",))),
    ],
)
def test_a_question_names_devices_the_way_a_command_does(said: str, question: Question) -> None:
    assert read_question(said, DeviceRefs(STAIRS)) == question


@pytest.mark.parametrize("said", ["stop at the kitchen", "stop the garage light", "is the kettle on?"])
def test_a_place_or_a_missing_device_is_not_a_device(said: str) -> None:
    refs = DeviceRefs(STAIRS)
    assert read_stop(said, refs) is None and read_question(said, refs) is None
