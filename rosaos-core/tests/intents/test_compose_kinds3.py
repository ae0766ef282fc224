"""Compositional understanding, third round: kinds of language a new writer used that the engine
did not yet read. Questions wrapped in openers, time words, tags and indirect frames, and about
brightness, colour and volume; a guessed question answered rather than offered back; the top
and bottom of a level; "it" and "that light" after a remark, "the one in …"; a kind of music
with no verb, a named track in the user's own words; whites by name; an exclamation before the
commands; the Reachy's head by other verbs; a robot sent back to charge; "whoa" before a request
is no stop, while "make the dog stop" is one. Each kind is checked on several sentences, and
against what must stay refused.
"""

from __future__ import annotations

from typing import Any

import pytest

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.state_words import colour
from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.intents.understanding.questions import Question, read_question
from rosaos.intents.understanding.stop_words import DeviceRefs, StopRequest, read_stop

from .intents_support import home_world
from .intents_support import matcher_for as _matcher
from .intents_support import plan_calls as _calls

Call = tuple[str, str, dict[str, Any]]


@pytest.fixture(scope="module")
def home() -> IntentMatcher:
    return _matcher(
        {
            "kitchen_light": DeviceConfig(driver="tapo", description="Ceiling light in the kitchen"),
            "hall_light": DeviceConfig(driver="tapo", description="Ceiling light in the hallway"),
            "sofa_lamp": DeviceConfig(driver="tapo", description="Floor lamp next to the sofa in the lounge"),
            "spotify": DeviceConfig(driver="spotify", description="Music on the lounge speaker"),
        }
    )


@pytest.fixture(scope="module")
def lab() -> IntentMatcher:
    return _matcher(
        {
            "reachy": DeviceConfig(driver="reachy", description="Reachy Mini desktop robot on the desk"),
            "rover": DeviceConfig(driver="ros", description="TurtleBot4 wheeled robot with a charging dock"),
        }
    )


@pytest.fixture(scope="module")
def refs() -> DeviceRefs:
    return DeviceRefs(
        [*home_world(), DeviceVocabulary(name="dog", driver="ros", description="Hiwonder PuppyPi robot dog")]
    )


@pytest.mark.parametrize(
    ("said", "question"),
    [
        ("hey, is the kitchen light on right now?", Question("on", ("kitchen_light",))),
        ("is the bedroom light on, do you know?", Question("on", ("bedroom_light",))),
        ("Is the turtlebot still sitting on its dock?", Question("docked", ("turtlebot",))),
        ("did we leave the kitchen light on?", Question("on", ("kitchen_light",))),
        ("do you happen to know if the dog is moving", Question("busy", ("dog",))),
        ("can you tell me where the dog is", Question("position", ("dog",))),
        ("how bright is the living room lamp at the moment?", Question("brightness", ("living_room_lamp",))),
        ("what level is the bedroom light set to", Question("brightness", ("bedroom_light",))),
        ("what colour is the kitchen light currently?", Question("colour", ("kitchen_light",))),
        ("could you tell me what colour the kitchen light is", Question("colour", ("kitchen_light",))),
        ("how loud is the music", Question("volume", ("speaker",))),
        ("what's the volume at?", Question("volume", ())),
        ("oh what's this song that's playing?", Question("playing", ())),
        ("who's singing?", Question("playing", ())),
    ],
)
def test_what_is_around_a_question_does_not_change_what_it_asks(
    said: str, question: Question, refs: DeviceRefs
) -> None:
    assert read_question(said, refs) == question


@pytest.mark.parametrize(
    "said",
    [
        "is the kettle on right now?",
        "can you turn on the light?",
        "what time is it",
        "what's the weather like",
    ],
)
def test_other_questions_and_requests_are_not_state_questions(said: str, refs: DeviceRefs) -> None:
    assert read_question(said, refs) is None


@pytest.mark.parametrize(
    ("state", "words"),
    [
        ({"hue": 240, "saturation": 100, "color_temp": 0}, "blue"),
        ({"hue": 0, "saturation": 100, "color_temp": 0}, "red"),
        ({"hue": 0, "saturation": 0, "color_temp": 2700}, "warm white (2700 K)"),
        ({"hue": 0, "saturation": 0, "color_temp": 6500}, "cool white (6500 K)"),
        ({"is_playing": True}, None),
    ],
)
def test_a_lights_colour_is_said_in_words(state: dict[str, Any], words: str | None) -> None:
    assert colour(state) == words


def test_a_question_the_engine_guessed_is_answered_not_offered_back(home: IntentMatcher) -> None:
    result = home.match("How bright is the sofa lamp at the moment, thanks?")
    assert result.kind == "plans"
    assert {step[1] for step in _calls(result)} == {"get_state"}


@pytest.mark.parametrize(
    ("said", "calls"),
    [
        ("kitchen light all the way up please", [("kitchen_light", "set_brightness", {"brightness": 100})]),
        ("music as loud as it goes", [("spotify", "set_volume", {"volume": 100})]),
        (
            "turn the kitchen light all the way down",
            [("kitchen_light", "adjust_brightness", {"change": -100})],
        ),
        ("put the music on the lowest setting", [("spotify", "change_volume", {"delta": -100})]),
    ],
)
def test_the_top_and_the_bottom_of_a_level(said: str, calls: list[Call], home: IntentMatcher) -> None:
    assert _calls(home.match(said)) == calls


@pytest.mark.parametrize(
    ("said", "calls"),
    [
        ("hmm, it's a bit loud, turn it down a little", [("spotify", "change_volume", {"delta": -10})]),
        ("the kitchen feels cold, make that light a little warmer", [("kitchen_light", "adjust_color_temp", {"change": -500})]),
        ("the hallway is gloomy, put that light on", [("hall_light", "turn_on", {})]),
        ("turn on the kitchen light and switch off the one in the hall",
         [("kitchen_light", "turn_on", {}), ("hall_light", "turn_off", {})]),
    ],
)  # fmt: skip
def test_what_was_just_said_names_the_device(said: str, calls: list[Call], home: IntentMatcher) -> None:
    assert _calls(home.match(said)) == calls


def test_that_light_with_nothing_said_before_still_asks_which(home: IntentMatcher) -> None:
    assert home.match("make that light a little warmer").kind == "clarify"


@pytest.mark.parametrize(
    ("said", "query"),
    [
        ("I'd love some jazz in the lounge right now", "jazz"),
        ("how about some classical music", "classical"),
        ("we could do with a bit of reggae", "reggae"),
        ("could you maybe play Take Five?", "Take Five"),
        ("I'd like to hear Here Comes the Sun", "Here Comes the Sun"),
    ],
)
def test_music_by_its_kind_or_its_name_as_said(said: str, query: str, home: IntentMatcher) -> None:
    assert _calls(home.match(said)) == [("spotify", "play", {"query": query})]


@pytest.mark.parametrize(
    ("said", "calls"),
    [
        ("switch the sofa lamp back to plain warm white", [("sofa_lamp", "set_color_name", {"name": "warm white"})]),
        ("dim the lamp next to the couch a little", [("sofa_lamp", "adjust_brightness", {"change": -10})]),
        ("Movie night! Dim the sofa lamp to 20 percent and pause the music.",
         [("sofa_lamp", "set_brightness", {"brightness": 20}), ("spotify", "pause", {})]),
    ],
)  # fmt: skip
def test_whites_synonyms_and_an_exclamation(said: str, calls: list[Call], home: IntentMatcher) -> None:
    assert _calls(home.match(said)) == calls


@pytest.mark.parametrize(
    "said",
    ["the tv, turn it on", "turn on the garage light", "finally some peace and quiet", "don't play any jazz"],
)
def test_what_names_no_device_here_or_refuses_is_not_acted_on(said: str, home: IntentMatcher) -> None:
    assert not home.match(said).is_exact


@pytest.mark.parametrize(
    ("said", "direction"),
    [
        ("Reachy, could you look up at the ceiling for a sec?", "up"),
        ("Reachy, glance over to your right.", "right"),
        ("tilt your head down a little, reachy", "down"),
        ("reachy, lift your head", "up"),
        ("reachy, look at the floor", "down"),
        ("turn your head to the right, Reachy", "right"),
    ],
)
def test_the_reachys_head_by_other_verbs(said: str, direction: str, lab: IntentMatcher) -> None:
    assert _calls(lab.match(said)) == [("reachy", "look", {"direction": direction})]


def test_facing_forward_turns_the_body_then_the_head(lab: IntentMatcher) -> None:
    assert _calls(lab.match("okay Reachy, face forward again")) == [
        ("reachy", "rotate_body", {"degrees": 0}),
        ("reachy", "look", {"direction": "front"}),
    ]


@pytest.mark.parametrize(
    "said",
    [
        "okay we're done for the day, send the rover back to charge",
        "rover, head home now",
        "time for the rover to go and charge up",
        "take the rover back to its charger",
    ],
)
def test_going_home_or_to_charge_is_docking(said: str, lab: IntentMatcher) -> None:
    assert _calls(lab.match(said)) == [("rover", "dock", {})]


@pytest.mark.parametrize(
    ("said", "stop"),
    [
        ("whoa, the music is way too loud, turn it down a lot", None),
        ("hold on, turn on the kitchen light", None),
        ("whoa, whoa", StopRequest(())),
        ("whoa, the dog is going too far", StopRequest((), "the dog is going too far")),
        ("make the dog stop", StopRequest(("dog",))),
        ("get the dog to stop", StopRequest(("dog",))),
        ("tell the turtlebot to halt", StopRequest(("turtlebot",))),
        ("woah, make the dog stop spinning", StopRequest(("dog",))),
    ],
)
def test_whoa_before_a_request_is_no_stop_and_make_it_stop_is_one(
    said: str, stop: StopRequest | None, refs: DeviceRefs
) -> None:
    assert read_stop(said, refs) == stop


@pytest.mark.parametrize(
    ("said", "calls"),
    [
        ("make the lounge cosy", [("sofa_lamp", "set_color_temp", {"kelvin": 2700}), ("sofa_lamp", "set_brightness", {"brightness": 40})]),
        ("movie night in the lounge", [("sofa_lamp", "set_brightness", {"brightness": 20})]),
    ],
)  # fmt: skip
def test_a_scene_sets_the_devices_of_the_place_it_names(
    said: str, calls: list[Call], home: IntentMatcher
) -> None:
    assert _calls(home.match(said)) == calls


def test_a_scene_with_no_place_and_lights_in_several_rooms_asks_which(home: IntentMatcher) -> None:
    assert home.match("make it cosy in here").kind == "clarify"


@pytest.mark.parametrize(
    ("said", "text"),
    [
        ("have Reachy say good night to everyone", "good night to everyone"),
        ("Reachy, let everyone know the pizza's here", "the pizza's here"),
        ("get reachy to tell everybody that Lunch is ready", "Lunch is ready"),
    ],
)
def test_words_to_say_are_said_as_written(said: str, text: str, lab: IntentMatcher) -> None:
    assert _calls(lab.match(said)) == [("reachy", "speak", {"text": text})]
