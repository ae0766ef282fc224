"""Compositional understanding, seventh round (helper lang7b): a device named by what it is next
to or stands on, in any clause ("the one by the bed", "the kitchen one"); hesitations and restarts
inside a command, never inside words to be said; how loud, said after the music; a robot
addressed before a remark; words told to the dog, said to it in the second person.
"""

from __future__ import annotations

from typing import Any

import pytest

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.vocabulary import sources_from_config
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.plugins import load_drivers

from .intents_support import plan_calls as _calls

Call = tuple[str, str, dict[str, Any]]


@pytest.fixture(scope="module")
def home() -> IntentMatcher:
    devices = {
        "bedside": DeviceConfig(driver="tapo", description="Bedside lamp in the bedroom"),
        "ceiling": DeviceConfig(driver="tapo", description="Ceiling light in the bedroom"),
        "kitchen": DeviceConfig(driver="tapo", description="Ceiling light in the kitchen"),
        "sofa_lamp": DeviceConfig(driver="tapo", description="Floor lamp next to the sofa"),
        "dining": DeviceConfig(driver="tapo", description="Lamp above the dining table"),
        "speaker": DeviceConfig(driver="spotify", description="Music on the living room speaker"),
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


@pytest.fixture(scope="module")
def lab() -> IntentMatcher:
    devices = {
        "reachy": DeviceConfig(driver="reachy", description="Reachy Mini desktop robot"),
        "dog": DeviceConfig(driver="ros", description="Hiwonder PuppyPi quadruped robot dog"),
        "desk_lamp": DeviceConfig(driver="tapo", description="Lamp on the desk, next to the window"),
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("switch on the one by the bed", [("bedside", "turn_on", {})]),
        ("turn on the light next to my bed", [("bedside", "turn_on", {})]),
        ("put the lamp on the nightstand on", [("bedside", "turn_on", {})]),
        ("turn on the light over the table", [("dining", "turn_on", {})]),
        ("dim the lamp by my bed", [("bedside", "adjust_brightness", {"change": -20})]),
        (
            "turn off the kitchen one and switch on the one by the sofa",
            [("kitchen", "turn_off", {}), ("sofa_lamp", "turn_on", {})],
        ),
        (
            "switch off the kitchen one, then turn on the one next to the couch",
            [("kitchen", "turn_off", {}), ("sofa_lamp", "turn_on", {})],
        ),
    ],
)
def test_a_device_is_named_by_what_it_is_next_to(
    home: IntentMatcher, said: str, expected: list[Call]
) -> None:
    assert _calls(home.match(said)) == expected


@pytest.fixture(scope="module")
def house() -> IntentMatcher:
    devices = {
        "reading": DeviceConfig(driver="tapo", description="Reading lamp next to the armchair in the study"),
        "floor": DeviceConfig(driver="tapo", description="Floor lamp in the living room, next to the window"),
        "night": DeviceConfig(driver="tapo", description="Night light in the nursery"),
        "porch": DeviceConfig(driver="tapo", description="Light outside by the front door"),
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("switch on the one next to the chair", [("reading", "turn_on", {})]),
        ("turn on the light in the baby's room", [("night", "turn_on", {})]),
        ("turn off the light by the door", [("porch", "turn_off", {})]),
        ("turn on the light by the window", [("floor", "turn_on", {})]),
    ],
)
def test_a_part_of_a_compound_word_or_who_uses_a_room_names_it(
    house: IntentMatcher, said: str, expected: list[Call]
) -> None:
    assert _calls(house.match(said)) == expected


def test_the_one_in_a_room_with_two_asks_which(home: IntentMatcher) -> None:
    result = home.match("turn our bedroom one on")
    assert result.kind == "clarify" and not result.processes
    assert "bedside" in result.reply and "ceiling" in result.reply


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("can you play, like, some classical music", [("speaker", "play", {"query": "classical"})]),
        ("turn the, um, the kitchen light off", [("kitchen", "turn_off", {})]),
        (
            "set the dining light to, you know, forty percent",
            [("dining", "set_brightness", {"brightness": 40})],
        ),
        ("could you uh switch on the uh lamp by the sofa", [("sofa_lamp", "turn_on", {})]),
        ("turn off the, the kitchen light", [("kitchen", "turn_off", {})]),
        ("put on Kind of Blue", [("speaker", "play", {"query": "Kind of Blue"})]),
    ],
)
def test_hesitations_inside_a_command_are_dropped(
    home: IntentMatcher, said: str, expected: list[Call]
) -> None:
    assert _calls(home.match(said)) == expected


def test_hesitations_inside_words_to_say_are_kept(lab: IntentMatcher) -> None:
    [(device, tool, args)] = _calls(lab.match("say um, hello there"))
    assert (device, tool) == ("reachy", "speak") and args["text"].startswith("um")


@pytest.mark.parametrize(
    ("said", "query", "volume"),
    [
        ("play Clair de Lune by Debussy at volume twenty-five", "Clair de Lune by Debussy", 25),
        ("put on some jazz, volume 30", "jazz", 30),
        ("put on Dolly Parton at 20 percent volume", "Dolly Parton", 20),
        ("play some rock really loud", "rock", 80),
        ("play Jolene quietly please", "Jolene", 25),
    ],
)
def test_how_loud_after_the_music_sets_the_volume_and_stays_out_of_the_search(
    home: IntentMatcher, said: str, query: str, volume: int
) -> None:
    assert _calls(home.match(said)) == [
        ("speaker", "play", {"query": query}),
        ("speaker", "set_volume", {"volume": volume}),
    ]


def test_something_quiet_is_what_to_play(home: IntentMatcher) -> None:
    calls = _calls(home.match("play something quiet"))
    assert [tool for _, tool, _ in calls] == ["play"]


@pytest.mark.parametrize(
    "said",
    [
        "Reachy, we're done for today, you can go to sleep now",
        "reachy, it's been a long day, go to sleep",
        "ok robot, time for bed",
    ],
)
def test_a_robot_addressed_before_a_remark_is_the_one_commanded(lab: IntentMatcher, said: str) -> None:
    assert _calls(lab.match(said)) == [("reachy", "sleep", {})]


@pytest.mark.parametrize(
    ("said", "spoken"),
    [
        ("say I love you to the doggy", "I love you"),
        ("tell the dog I love it", "I love you"),
        ("reachy, tell the dog he's a very good boy", "you're a very good boy"),
        ("have Reachy say good night to everyone", "good night to everyone"),
    ],
)
def test_words_told_to_the_dog_are_said_to_it_never_an_order_to_it(
    lab: IntentMatcher, said: str, spoken: str
) -> None:
    assert _calls(lab.match(said)) == [("reachy", "speak", {"text": spoken})]


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("can you play like some jazz", [("speaker", "play", {"query": "jazz"})]),
        ("turn off the stupid kitchen light", [("kitchen", "turn_off", {})]),
        ("turn on the damn dining light please", [("dining", "turn_on", {})]),
        ("play some jazz or something", [("speaker", "play", {"query": "jazz"})]),
        ("play something like jazz", [("speaker", "play", {"query": "something like jazz"})]),
    ],
)
def test_feeling_words_and_vague_tails_say_nothing_of_which(
    home: IntentMatcher, said: str, expected: list[Call]
) -> None:
    assert _calls(home.match(said)) == expected


@pytest.mark.parametrize(
    ("said", "query", "volume"),
    [
        ("play Jolene at a low volume", "Jolene", 25),
        ("play jazz at max volume", "jazz", 100),
        ("put some jazz on at volume 40", "jazz", 40),
        ("play something by Miles Davis, not too loud", "Miles Davis", 35),
        ("put on some classical music nice and quiet", "classical music", 25),
    ],
)
def test_more_ways_to_say_how_loud(home: IntentMatcher, said: str, query: str, volume: int) -> None:
    assert _calls(home.match(said)) == [
        ("speaker", "play", {"query": query}),
        ("speaker", "set_volume", {"volume": volume}),
    ]


@pytest.mark.parametrize(
    "said",
    [
        "good night reachy, sleep well",
        "alright little robot, bedtime",
        "thanks reachy, you can rest now",
        "alright reachy, that's all for today, off to sleep you go",
    ],
)
def test_good_night_to_a_robot_is_sleep(lab: IntentMatcher, said: str) -> None:
    assert _calls(lab.match(said)) == [("reachy", "sleep", {})]


def test_the_front_door_is_a_place_not_a_pose(house: IntentMatcher) -> None:
    assert _calls(house.match("um turn off the light by the front door")) == [("porch", "turn_off", {})]
