"""Compositional understanding, fourth round: politeness with its own verb ("would you be kind
enough to …") and a term of address set off by a comma ("…, love"); a need said before the
command ("I need good light for reading, …"); a play request whose search ran on past a comma
into a reason; "not this one" before a skip. Each kind on several sentences, and against what
must stay as it was: a refusal, "enough" as a stop, a search that is a title.
"""

from __future__ import annotations

from typing import Any

import pytest

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.vocabulary import sources_from_config
from rosaos.intents.understanding.compose.speech import command_words, negated, normalise, says_stop
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.plugins import load_drivers

from .intents_support import plan_calls as _calls

Call = tuple[str, str, dict[str, Any]]


@pytest.fixture(scope="module")
def home() -> IntentMatcher:
    devices = {
        "desk_lamp": DeviceConfig(driver="tapo", description="Desk lamp in the study"),
        "porch_light": DeviceConfig(driver="tapo", description="Light outside by the front door"),
        "speaker": DeviceConfig(driver="spotify", description="Music on the kitchen speaker"),
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


@pytest.mark.parametrize(
    ("said", "command"),
    [
        ("would you be so kind as to open the blinds, dear", "open the blinds"),
        ("could you be kind enough to dim the lamp", "dim the lamp"),
        ("please be good enough to stop the music", "stop the music"),
        ("i'd appreciate it if you could close the door, my friend", "close the door"),
        ("honey, turn the radio on", "turn the radio on"),
        ("turn the lamp off for me, love", "turn the lamp off"),
    ],
)
def test_politeness_and_address_are_peeled_off_whatever_the_command(said: str, command: str) -> None:
    assert command_words(normalise(said)) == command


def test_a_word_of_address_without_its_comma_is_part_of_the_command() -> None:
    assert command_words(normalise("play something I love")) == "play something i love"


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("Would you be kind enough to put the desk lamp on, sweetheart?", [("desk_lamp", "turn_on", {})]),
        ("Love, would you be good enough to switch off the porch light", [("porch_light", "turn_off", {})]),
        ("I need good light for reading, turn on the desk lamp", [("desk_lamp", "turn_on", {})]),
        ("we want to eat outside, switch the porch light off", [("porch_light", "turn_off", {})]),
        ("I need to concentrate, turn the music off", [("speaker", "pause", {})]),
        ("put on some jazz, I need to unwind", [("speaker", "play", {"query": "jazz"})]),
        ("play something classical, we're having dinner", [("speaker", "play", {"query": "classical"})]),
        ("ugh, not this one, skip it", [("speaker", "next_track", {})]),
        ("nah, not that song, next", [("speaker", "next_track", {})]),
    ],
)
def test_the_command_is_done_and_the_wrapping_or_the_reason_dropped(
    home: IntentMatcher, said: str, expected: list[Call]
) -> None:
    assert _calls(home.match(said)) == expected


def test_a_title_is_searched_whole_and_a_comma_in_it_is_no_reason(home: IntentMatcher) -> None:
    assert _calls(home.match("play hello, goodbye")) == [("speaker", "play", {"query": "hello goodbye"})]
    assert _calls(home.match("play something I love")) == [("speaker", "play", {"query": "something I love"})]


def test_kind_enough_is_no_stop_and_enough_alone_still_is() -> None:
    assert not says_stop(normalise("could you be kind enough to dim the lamp"))
    assert says_stop(normalise("okay, that's enough"))


def test_a_refusal_stays_a_refusal_and_not_this_one_alone_is_no_refusal() -> None:
    assert negated(normalise("don't turn on the desk lamp, dear"))
    assert negated(normalise("not the desk lamp"))
    assert not negated(normalise("not this one, skip it"))
