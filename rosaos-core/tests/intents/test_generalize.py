"""Everyday sentences: fillers, names said first or last, negations, kinds as names, fuzzy guesses.

Run against the test home world (the test drivers' templates) and, where a built-in driver's
templates matter (relative changes, "all the lights", areas), against the real drivers.
"""

from __future__ import annotations

import pytest

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.vocabulary import sources_from_config
from rosaos.intents.understanding.fuzzy import ACT_SCORE, ASK_SCORE
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.intents.understanding.rephrase import join_split_names, negated, strip_fillers
from rosaos.plugins import load_drivers

from .intents_support import plan_calls as _calls


@pytest.fixture(scope="module")
def real() -> IntentMatcher:
    """A world on the built-in drivers: three lights in three rooms, music, two robots, Reachy."""
    devices = {
        "kitchen_light": DeviceConfig(driver="tapo", description="Ceiling light in the kitchen"),
        "living_room_lamp": DeviceConfig(driver="tapo", description="Floor lamp in the living room"),
        "bedroom_light": DeviceConfig(driver="tapo", description="Bedside light in the bedroom"),
        "spotify": DeviceConfig(driver="spotify", description="Music on the living room speaker"),
        "turtlebot": DeviceConfig(driver="ros", description="TurtleBot4 wheeled mobile robot"),
        "dog": DeviceConfig(driver="ros", description="Hiwonder PuppyPi quadruped robot dog"),
        "reachy": DeviceConfig(driver="reachy", description="Reachy Mini desktop robot"),
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


# Rephrasing, as plain functions


def test_fillers_around_a_command_are_dropped() -> None:
    assert strip_fillers("Could you please turn on the lamp for me, thanks", "en") == "turn on the lamp"


def test_a_negated_command_is_read_without_its_negation() -> None:
    assert negated("Please don't turn on the lamp", "en") == "turn on the lamp"
    assert negated("I don't like this song", "en") is None


def test_a_name_speech_to_text_split_is_joined() -> None:
    assert join_split_names("send the turtle bot home", ["turtlebot", "dog"]) == "send the turtlebot home"


# The matcher


def test_a_negated_command_is_refused_by_name_and_nothing_runs(matcher: IntentMatcher) -> None:
    result = matcher.match("Don't turn on the kitchen light")
    assert (result.kind, result.processes, result.refusal) == ("no_match", (), True)
    assert result.reply == "All right, I won't turn on the kitchen light. Nothing was changed."


def test_a_name_said_first_is_the_device_the_command_is_for(real: IntentMatcher) -> None:
    assert _calls(real.match("Turtlebot, go one meter ahead")) == [
        ("turtlebot", "move_distance", {"meters": 1})
    ]


def test_a_name_said_last_is_the_device_the_command_is_for(real: IntentMatcher) -> None:
    assert _calls(real.match("Turn your head to the right, Reachy")) == [
        ("reachy", "look", {"direction": "right"})
    ]


def test_a_kind_one_device_has_names_it_and_a_shared_kind_asks(real: IntentMatcher) -> None:
    assert _calls(real.match("Lamp off")) == [("living_room_lamp", "turn_off", {})]
    assert _calls(real.match("Walk the pup forward")) == [("dog", "move_distance", {"meters": 0.5})]
    asked = real.match("Move the robot forward")
    assert asked.kind == "clarify"
    assert "turtlebot" in asked.reply and "dog" in asked.reply


def test_relative_changes_have_the_size_people_say(real: IntentMatcher) -> None:
    assert _calls(real.match("Make the lamp a bit brighter")) == [
        ("living_room_lamp", "adjust_brightness", {"change": 15})
    ]
    assert _calls(real.match("Make the lamp much dimmer")) == [
        ("living_room_lamp", "adjust_brightness", {"change": -40})
    ]
    assert _calls(real.match("Make the kitchen light warmer")) == [
        ("kitchen_light", "adjust_color_temp", {"change": -700})
    ]


def test_all_the_lights_with_a_value_reaches_every_light(real: IntentMatcher) -> None:
    calls = _calls(real.match("All the lights to 40%"))
    assert sorted(calls) == [
        (name, "set_brightness", {"brightness": 40})
        for name in ("bedroom_light", "kitchen_light", "living_room_lamp")
    ]


def test_a_need_in_an_area_acts_on_the_light_there(real: IntentMatcher) -> None:
    assert _calls(real.match("It's too dark in the bedroom")) == [("bedroom_light", "turn_on", {})]


@pytest.mark.parametrize(
    "sentence",
    [
        "Don't move the dog",
        "Open the blinds",
        "Stop the drone",
        "Set the lamp to 300 kelvin",
        "Set the kitchen light to -5 percent",
        "What's the weather like",
        "The desk lamp",
    ],
)
def test_what_must_change_nothing_is_never_guessed_into_an_action(real: IntentMatcher, sentence: str) -> None:
    result = real.match(sentence)
    assert not result.is_exact or {tool for _, tool, _ in _calls(result)} <= {"get_state"}


# Fuzzy guesses


def test_a_weak_guess_asks_did_you_mean_and_does_nothing(matcher: IntentMatcher) -> None:
    result = matcher.match("could the kitchen light go off")
    assert (result.kind, result.processes) == ("clarify", ())
    assert result.reply == f"Did you mean: {result.suggestion}?"
    assert _calls(matcher.match(result.suggestion)) == [("kitchen_light", "turn_off", {})]


def test_yes_to_did_you_mean_is_the_suggested_command(matcher: IntentMatcher) -> None:
    confirmed = matcher.follow_up("could the kitchen light go off", "Yes please")
    assert confirmed is not None
    assert _calls(confirmed) == [("kitchen_light", "turn_off", {})]
    assert matcher.follow_up("could the kitchen light go off", "the bedroom") is None


def test_a_close_guess_acts(real: IntentMatcher) -> None:
    guess = real._fuzzy.guess("kitchen light brightness 30")
    assert guess is not None and guess.score >= ACT_SCORE
    assert _calls(real.match("kitchen light brightness 30")) == [
        ("kitchen_light", "set_brightness", {"brightness": 30})
    ]


def test_words_no_template_uses_keep_a_sentence_far_from_every_template(real: IntentMatcher) -> None:
    guess = real._fuzzy.guess("what's the weather like in Paris tomorrow")
    assert guess is None or guess.score < ASK_SCORE


def test_the_fuzzy_model_is_deterministic(real: IntentMatcher) -> None:
    assert real._fuzzy.guess("could the bedroom light go off") == real._fuzzy.guess(
        "could the bedroom light go off"
    )
