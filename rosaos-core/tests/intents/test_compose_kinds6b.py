"""Compositional understanding, sixth round (phrase kinds). First, safety: a wish for a colour
nobody knows ("I want the lamp to be plaid") changes nothing and says what it did not know (it
once turned the lamp on at 100 %), and a time inside words to say ("announce that the meeting
starts in five minutes") is never a timer. Then: a wish is its command; one device with a list of
settings and hedged numbers; music with an occasion or purpose searches only the music; the
Reachy's announcements, a learner's "you say", and a direction said after what to look at.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

import pytest

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.vocabulary import sources_from_config
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.intents.understanding.readings import search_words
from rosaos.plugins import load_drivers
from rosaos.timers.timer_phrases import SetTimer, read_timer_request

from .intents_support import plan_calls as _calls

Call = tuple[str, str, dict[str, Any]]


@pytest.fixture(scope="module")
def home() -> IntentMatcher:
    devices = {
        "porch": DeviceConfig(driver="tapo", description="Light over the front porch"),
        "desk_lamp": DeviceConfig(driver="tapo", description="Desk lamp in the study"),
        "speaker": DeviceConfig(driver="spotify", description="Music on the kitchen speaker"),
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


@pytest.fixture(scope="module")
def lab() -> IntentMatcher:
    devices = {
        "reachy": DeviceConfig(driver="reachy", description="Reachy Mini desktop robot"),
        "bench_lamp": DeviceConfig(driver="tapo", description="Lamp on the bench"),
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


@pytest.mark.parametrize(
    ("said", "unknown"),
    [
        ("I want the porch light to be plaid", "plaid"),
        ("I'd like my desk lamp to be chartreuse please", "chartreuse"),
        ("we need the desk lamp to be polka dot", "polka dot"),
    ],
)
def test_a_wish_for_an_unknown_colour_changes_nothing_and_says_so(
    home: IntentMatcher, said: str, unknown: str
) -> None:
    result = home.match(said)
    assert result.kind == "no_match" and not result.processes
    assert f'"{unknown}"' in result.reply


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("I want my desk lamp to be purple", [("desk_lamp", "set_color_name", {"name": "purple"})]),
        (
            "we'd really love the porch light to be turquoise",
            [("porch", "set_color_name", {"name": "turquoise"})],
        ),
        (
            "okay so I'd like the desk lamp to be lavender",
            [("desk_lamp", "set_color_name", {"name": "lavender"})],
        ),
        ("can we have the porch light at 40 percent", [("porch", "set_brightness", {"brightness": 40})]),
        ("could I get the desk lamp off", [("desk_lamp", "turn_off", {})]),
        ("I want the speaker to be quieter", [("speaker", "change_volume", {"delta": -15})]),
        ("make the porch light gold", [("porch", "set_color_name", {"name": "gold"})]),
        ("turn the desk lamp navy", [("desk_lamp", "set_color_name", {"name": "navy"})]),
    ],
)
def test_a_wish_is_the_command_it_asks_for(home: IntentMatcher, said: str, expected: list[Call]) -> None:
    result = home.match(said)
    assert result.kind == "plans" and _calls(result) == expected


def test_a_wish_for_music_is_no_wish_for_a_state(home: IntentMatcher) -> None:
    result = home.match("I'd like the jazz playlist")
    assert result.kind == "plans" and _calls(result) == [("speaker", "play", {"query": "jazz"})]


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        (
            "desk lamp on, blue, and not too bright, like 30 percent",
            [
                ("desk_lamp", "turn_on", {}),
                ("desk_lamp", "set_color_name", {"name": "blue"}),
                ("desk_lamp", "set_brightness", {"brightness": 30}),
            ],
        ),
        (
            "porch light: warm white, half brightness",
            [
                ("porch", "set_color_name", {"name": "warm white"}),
                ("porch", "set_brightness", {"brightness": 50}),
            ],
        ),
        ("set the porch light to about 25", [("porch", "set_brightness", {"brightness": 25})]),
        ("the porch light, not too bright", [("porch", "adjust_brightness", {"change": -20})]),
        ("speaker not too loud", [("speaker", "change_volume", {"delta": -20})]),
    ],
)
def test_one_device_with_a_list_of_settings_gets_them_all(
    home: IntentMatcher, said: str, expected: list[Call]
) -> None:
    result = home.match(said)
    assert result.kind == "plans" and _calls(result) == expected


@pytest.mark.parametrize(
    ("said", "query"),
    [
        ("put on some Miles Davis while we work", "Miles Davis"),
        ("play some jazz for dinner", "jazz"),
        ("something by the Beatles to relax", "the Beatles"),
        ("put something on by the Beatles, would you?", "the Beatles"),
        ("play some Debussy during dinner", "Debussy"),
        ("put on Kind of Blue while I'm cooking", "Kind of Blue"),
    ],
)
def test_music_with_an_occasion_searches_only_the_music(home: IntentMatcher, said: str, query: str) -> None:
    result = home.match(said)
    assert result.kind == "plans" and _calls(result) == [("speaker", "play", {"query": query})]


@pytest.mark.parametrize("title", ["While My Guitar Gently Weeps", "Born to Run", "Music for Airports"])
def test_a_title_with_while_to_or_for_keeps_its_words(title: str) -> None:
    assert search_words(title) == title


@pytest.mark.parametrize(
    ("said", "spoken"),
    [
        ("announce that the meeting starts in five minutes", "the meeting starts in five minutes"),
        ("tell everyone that dinner is ready", "dinner is ready"),
        ("let them know the pizza is here", "the pizza is here"),
        ("please you say hello to my friend Anna", "hello to my friend Anna"),
    ],
)
def test_words_to_say_are_said_now(lab: IntentMatcher, said: str, spoken: str) -> None:
    result = lab.match(said)
    assert result.kind == "plans" and _calls(result) == [("reachy", "speak", {"text": spoken})]


@pytest.mark.parametrize(
    "said",
    [
        "announce that the meeting starts in five minutes",
        "tell everyone that the bus leaves in 10 minutes",
        "let them know lunch is at 1 pm",
    ],
)
def test_a_time_inside_words_to_say_is_never_a_timer(said: str) -> None:
    assert read_timer_request(said, datetime.now(UTC).astimezone()) is None


def test_a_time_before_words_to_say_is_still_a_timer() -> None:
    found = read_timer_request("in five minutes say dinner is ready", datetime.now(UTC).astimezone())
    assert found == SetTimer(action="say dinner is ready", in_seconds=300.0)


@pytest.mark.parametrize(
    ("said", "direction"),
    [
        ("look at the window, it's on your left", "left"),
        ("glance at the door, it is to your right", "right"),
        ("turn your head to the plant, it's just on your left side", "left"),
    ],
)
def test_a_direction_said_after_what_to_look_at_turns_the_head(
    lab: IntentMatcher, said: str, direction: str
) -> None:
    result = lab.match(said)
    assert result.kind == "plans" and _calls(result) == [("reachy", "look", {"direction": direction})]
