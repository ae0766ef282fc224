"""Compositional understanding, fifth round. First, safety: a room said by its use ("the sleeping
room", "where we cook") or by another name ("the sitting room") is that room, and a room this
world lacks ("the games room") acts on nothing; "room" alone never picks a device (it once turned
off the living-room lamp for "the light of the sleeping room"). Then: a reason after a relative
request; a comparative white; the Reachy named around sleep, wake and say; a track said by what
it is about; and replies that call a device named after its product by that name.
"""

from __future__ import annotations

from typing import Any

import pytest

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.state_words import called, describe
from rosaos.intents.grammar.vocabulary import sources_from_config
from rosaos.intents.understanding.compose.places import name_places
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.intents.understanding.readings import search_words
from rosaos.plugins import load_drivers

from .intents_support import plan_calls as _calls

Call = tuple[str, str, dict[str, Any]]


@pytest.fixture(scope="module")
def home() -> IntentMatcher:
    devices = {
        "kitchen_light": DeviceConfig(driver="tapo", description="Ceiling light in the kitchen"),
        "lounge_lamp": DeviceConfig(driver="tapo", description="Floor lamp in the living room"),
        "bedside": DeviceConfig(driver="tapo", description="Bedside lamp in the bedroom"),
        "nursery_light": DeviceConfig(driver="tapo", description="Night light in the kids' room"),
        "spotify": DeviceConfig(driver="spotify", description="Music on the living room speaker"),
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


@pytest.fixture(scope="module")
def lab() -> IntentMatcher:
    devices = {
        "reachy": DeviceConfig(driver="reachy", description="Reachy Mini desktop robot"),
        "desk_lamp": DeviceConfig(driver="tapo", description="Lamp on the desk"),
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


@pytest.mark.parametrize(
    ("said", "room"),
    [
        ("the light of the sleeping room", "the light of the bedroom"),
        ("the lamp in the room where we usually eat", "the lamp in the dining"),
        ("the light where we cook", "the light the kitchen"),
        ("the cooking area light", "the kitchen light"),
        ("the sitting room lamp", "the living room lamp"),
        ("the light in the part of the house where the kids play", "the light in the nursery"),
        ("the living room lamp", "the living room lamp"),
        ("the games room", "the games room"),
    ],
)
def test_a_room_said_by_its_use_is_the_room_descriptions_name(said: str, room: str) -> None:
    assert name_places(said) == room


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("please, you make the light of the sleeping room off", [("bedside", "turn_off", {})]),
        ("switch off the light in the room where we sleep", [("bedside", "turn_off", {})]),
        ("turn on the light where we cook", [("kitchen_light", "turn_on", {})]),
        ("the lamp in the sitting room, switch it off", [("lounge_lamp", "turn_off", {})]),
        ("turn on the light in the children's room", [("nursery_light", "turn_on", {})]),
        ("turn the bedroom lamp on", [("bedside", "turn_on", {})]),
    ],
)
def test_a_room_by_its_use_or_another_name_acts_on_that_room(
    home: IntentMatcher, said: str, expected: list[Call]
) -> None:
    result = home.match(said)
    assert result.kind == "plans" and _calls(result) == expected


@pytest.mark.parametrize(
    "said",
    [
        "turn off the light in the games room",
        "you make the light of the guest room off",
        "switch the lamp in the laundry room on",
        "turn off the light in the waiting area",
    ],
)
def test_a_room_this_world_lacks_acts_on_nothing(home: IntentMatcher, said: str) -> None:
    result = home.match(said)
    assert result.kind != "plans" and not result.processes


def test_a_light_named_by_kind_alone_is_asked_about_listing_the_lights(home: IntentMatcher) -> None:
    result = home.match("switch the light of the room off")
    assert result.kind == "clarify" and not result.processes
    assert all(name in result.reply for name in ("kitchen light", "lounge lamp", "bedside"))


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        (
            "a little quieter please, the baby's finally asleep",
            [("spotify", "change_volume", {"delta": -10})],
        ),
        ("a bit louder, my dad's hard of hearing", [("spotify", "change_volume", {"delta": 10})]),
        ("skip this one, I'm not in the mood", [("spotify", "next_track", {})]),
        ("next song, I'm not really feeling it", [("spotify", "next_track", {})]),
    ],
)
def test_a_reason_after_a_relative_request_is_dropped(
    home: IntentMatcher, said: str, expected: list[Call]
) -> None:
    result = home.match(said)
    assert result.kind == "plans" and _calls(result) == expected


@pytest.mark.parametrize("said", ["don't skip this one", "I'm not sure, skip it", "never mind, turn it down"])
def test_a_negation_of_the_command_itself_still_does_nothing(home: IntentMatcher, said: str) -> None:
    assert not home.match(said).processes


@pytest.mark.parametrize(
    ("said", "device", "change"),
    [
        ("I'm reading in the kitchen, can you make that light a cooler white?", "kitchen_light", 700),
        ("make the bedside lamp a warmer white", "bedside", -700),
        ("the living room lamp is too yellow, make it less yellow", "lounge_lamp", 700),
    ],
)
def test_a_comparative_white_changes_the_colour_temperature(
    home: IntentMatcher, said: str, device: str, change: int
) -> None:
    result = home.match(said)
    assert _calls(result) == [(device, "adjust_color_temp", {"change": change})]


def test_a_plain_white_is_still_a_colour(home: IntentMatcher) -> None:
    assert _calls(home.match("make the kitchen light white")) == [
        ("kitchen_light", "set_color_name", {"name": "white"})
    ]


@pytest.mark.parametrize(
    ("said", "tool", "args"),
    [
        ("Reachy, go to sleep, we're done for today", "sleep", {}),
        ("Reachy, you can take a nap now, I'm off", "sleep", {}),
        ("time for bed, Reachy", "sleep", {}),
        ("Wake up, Reachy, time to work", "wake_up", {}),
        ("rise and shine, reachy", "wake_up", {}),
        ("Could the Reachy say hello to our visitors?", "speak", {"text": "hello to our visitors"}),
        ("can reachy say good morning", "speak", {"text": "good morning"}),
    ],
)
def test_the_reachy_named_around_sleep_wake_and_say(
    lab: IntentMatcher, said: str, tool: str, args: dict[str, Any]
) -> None:
    result = lab.match(said)
    assert result.kind == "plans" and _calls(result) == [("reachy", tool, args)]


@pytest.mark.parametrize("said", ["I really need some sleep", "time to turn on the desk lamp"])
def test_sleep_as_a_noun_is_no_order_to_sleep(lab: IntentMatcher, said: str) -> None:
    assert all(tool != "sleep" for _, tool, _ in _calls(lab.match(said)))


@pytest.mark.parametrize(
    ("said", "query"),
    [
        ("the sun song by the beatles", "sun by the beatles"),
        ("that rain song by the lovin' spoonful", "rain by the lovin' spoonful"),
        ("the moon song please", "moon"),
        ("your song by elton john", "your song by elton john"),
        ("so what", "so what"),
    ],
)
def test_a_track_said_by_what_it_is_about_is_searched_by_its_words(said: str, query: str) -> None:
    assert search_words(said) == query


def test_play_searches_a_described_track_by_its_words(home: IntentMatcher) -> None:
    assert _calls(home.match("play the sun song by the beatles")) == [
        ("spotify", "play", {"query": "sun by the beatles"})
    ]


def test_a_device_named_after_its_product_is_called_by_that_name() -> None:
    assert called("spotify", "spotify") == "Spotify"
    assert called("kitchen_light", "tapo") == "the kitchen light"
    said = describe("spotify", {"is_playing": True, "track": "So What", "volume": 40}, "spotify")
    assert said == ["Playing So What on Spotify.", "Spotify's volume is at 40%."]
