"""IntentMatcher: sentences to processes, or to a question / refusal that actuates nothing."""

from __future__ import annotations

from typing import Any

import pytest

from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.matching import IntentMatcher, MatchResult

from .intents_support import bulb, speaker


def calls(result: MatchResult) -> list[tuple[str, str, dict[str, Any]]]:
    """Every planned ``(device, tool, args)``, in process order."""
    return [
        (step.device, step.tool, step.args) for process in result.processes for step in process.plan.steps
    ]


# Names, aliases, areas


@pytest.mark.parametrize(
    ("sentence", "device"),
    [
        ("Turn on the kitchen light", "kitchen_light"),  # instance name, underscores as spaces
        ("turn on the plafonnier", "kitchen_light"),  # configured alias
        ("Turn on the floor lamp", "living_room_lamp"),  # "<thing> in the <area>" description
        ("Switch on the bedside light", "bedroom_light"),
        ("Turn on the lights in the bedroom", "bedroom_light"),  # area from the description
        ("please turn the kitchen light on", "kitchen_light"),  # HA skip words
    ],
)
def test_devices_are_found_by_name_alias_description_and_area(
    matcher: IntentMatcher, sentence: str, device: str
) -> None:
    assert calls(matcher.match(sentence)) == [(device, "turn_on", {})]


def test_a_driver_template_fills_its_tool_arguments(matcher: IntentMatcher) -> None:
    assert calls(matcher.match("Dim the living room lamp")) == [
        ("living_room_lamp", "adjust_brightness", {"change": -25})
    ]


@pytest.mark.parametrize(
    "sentence", ["Set the living room lamp to 20 percent", "set the living room lamp to 20%"]
)
def test_numbers_are_ints_not_floats(matcher: IntentMatcher, sentence: str) -> None:
    [(_, tool, args)] = calls(matcher.match(sentence))
    assert (tool, args) == ("set_brightness", {"brightness": 20})
    assert type(args["brightness"]) is int


def test_ha_intents_map_slots_to_the_driver_tool(matcher: IntentMatcher) -> None:
    assert calls(matcher.match("Make the bedroom light green")) == [
        ("bedroom_light", "set_color_name", {"name": "green"})
    ]


# All, ambiguous, unknown


def test_all_the_lights_is_one_process_per_light(matcher: IntentMatcher) -> None:
    result = matcher.match("Turn off all the lights")
    assert [process.devices for process in result.processes] == [
        ("kitchen_light",),
        ("living_room_lamp",),
        ("bedroom_light",),
    ]
    assert {step.tool for process in result.processes for step in process.plan.steps} == {"turn_off"}


@pytest.mark.parametrize("sentence", ["Turn off the light", "turn on the lights"])
def test_an_ambiguous_device_gets_a_question_naming_the_candidates(
    matcher: IntentMatcher, sentence: str
) -> None:
    result = matcher.match(sentence)
    assert (result.kind, result.processes) == ("clarify", ())
    assert result.reply == "Which one do you mean: kitchen light, living room lamp or bedroom light?"


def test_a_partial_name_asks_among_the_devices_it_fits(matcher: IntentMatcher) -> None:
    result = matcher.match("Dim the light")  # every light answers to its kind; a lamp is a light
    assert (result.kind, result.processes) == ("clarify", ())
    assert result.reply == "Which one do you mean: kitchen light, living room lamp or bedroom light?"


def test_an_unknown_device_of_a_known_kind_is_refused_naming_what_exists(matcher: IntentMatcher) -> None:
    result = matcher.match("Turn on the garage light")
    assert (result.kind, result.processes) == ("clarify", ())
    assert "garage light" in result.reply
    assert "kitchen light" in result.reply


@pytest.mark.parametrize("sentence", ["Tell the drone to take off", "turn on the fridge", "what", ""])
def test_anything_else_is_not_understood_and_lists_the_devices(matcher: IntentMatcher, sentence: str) -> None:
    result = matcher.match(sentence)
    assert (result.kind, result.processes) == ("no_match", ())
    assert "turtlebot" in result.reply


def test_a_device_that_cannot_do_it_is_refused(matcher: IntentMatcher) -> None:
    result = matcher.match("pause the kitchen light")
    assert result.kind != "plans"


# Questions


def test_a_yes_no_question_reads_the_state_and_carries_both_answers(matcher: IntentMatcher) -> None:
    [process] = matcher.match("Is the kitchen light on?").processes
    assert [(step.tool, step.args) for step in process.plan.steps] == [("get_state", {})]
    answer = process.plan.answer
    assert answer is not None
    assert answer.when == {"on": True}
    assert (answer.yes, answer.no) == ("Yes, the kitchen light is on.", "No, the kitchen light is off.")


def test_a_state_question_reads_the_state_aloud(matcher: IntentMatcher) -> None:
    [process] = matcher.match("What is the state of the bedroom light?").processes
    assert process.plan.answer is None
    assert "{result}" in process.plan.reply


# Several commands


def test_two_commands_become_two_processes(matcher: IntentMatcher) -> None:
    result = matcher.match("Turn on the kitchen light and play some jazz")
    assert calls(result) == [("kitchen_light", "turn_on", {}), ("speaker", "play", {"query": "jazz"})]
    assert [process.devices for process in result.processes] == [("kitchen_light",), ("speaker",)]


def test_a_wildcard_does_not_swallow_a_second_command(matcher: IntentMatcher) -> None:
    result = matcher.match("Play Clair de Lune and turn on the kitchen light")
    assert calls(result) == [
        ("speaker", "play", {"query": "Clair de Lune"}),
        ("kitchen_light", "turn_on", {}),
    ]


def test_a_title_with_and_stays_whole_when_nothing_else_matches(matcher: IntentMatcher) -> None:
    assert calls(matcher.match("Play Rock and Roll")) == [("speaker", "play", {"query": "Rock and Roll"})]


def test_two_commands_on_one_device_share_its_process(matcher: IntentMatcher) -> None:
    [process] = matcher.match("turn on the kitchen light, then set the kitchen light to 40%").processes
    assert [step.tool for step in process.plan.steps] == ["turn_on", "set_brightness"]


def test_one_unclear_command_stops_the_whole_sentence(matcher: IntentMatcher) -> None:
    result = matcher.match("Turn on the kitchen light and turn off the garage light")
    assert (result.kind, result.processes) == ("clarify", ())


# A device left out, as people do: the device of the command before, or the only one that fits


@pytest.mark.parametrize(
    "sentence",
    [
        "turn on the kitchen light and set it to 30 percent",  # a pronoun
        "turn on the kitchen light, then set to 30 percent",  # the name left out
    ],
)
def test_a_second_command_without_a_device_means_the_device_before(
    matcher: IntentMatcher, sentence: str
) -> None:
    result = matcher.match(sentence)
    assert [process.devices for process in result.processes] == [("kitchen_light",)]
    assert calls(result) == [
        ("kitchen_light", "turn_on", {}),
        ("kitchen_light", "set_brightness", {"brightness": 30}),
    ]
    # The task tells the process what the user said, not the engine's rewording.
    assert result.processes[0].summary.startswith("Turn on the kitchen light. Set ")


def test_a_device_left_out_is_not_carried_across_a_command_on_several(matcher: IntentMatcher) -> None:
    # "them" after "all the lights" could mean three devices: not guessed, not understood.
    result = matcher.match("turn on all the lights and set it to 30 percent")
    assert result.processes == ()


@pytest.mark.parametrize("sentence", ["set it to 30 percent", "set to 30 percent"])
def test_a_device_left_out_from_the_start_asks_among_those_that_fit(
    matcher: IntentMatcher, sentence: str
) -> None:
    result = matcher.match(sentence)
    assert (result.kind, result.processes) == ("clarify", ())
    for light in ("kitchen light", "living room lamp", "bedroom light"):
        assert light in result.reply
    assert "speaker" not in result.reply  # a speaker has no brightness
    answered = matcher.follow_up(sentence, "the bedroom one")
    assert answered is not None
    assert calls(answered) == [("bedroom_light", "set_brightness", {"brightness": 30})]


def test_a_device_left_out_means_the_only_one_that_fits() -> None:
    alone = IntentMatcher([bulb("desk_lamp", "Lamp on the desk"), speaker()], "en")
    assert calls(alone.match("set it to 30 percent")) == [("desk_lamp", "set_brightness", {"brightness": 30})]


def test_a_sentence_naming_no_known_device_is_still_not_understood(matcher: IntentMatcher) -> None:
    assert matcher.match("tell the drone to take off").kind == "no_match"


@pytest.mark.parametrize(
    ("sentence", "tool"),
    [
        ("Turn off the kitchen light and the bedroom light", "turn_off"),
        ("turn on the kitchen light, the bedroom light and the living room lamp", "turn_on"),
    ],
)
def test_a_list_of_names_repeats_the_command_for_each(
    matcher: IntentMatcher, sentence: str, tool: str
) -> None:
    result = matcher.match(sentence)
    assert {call[0] for call in calls(result)} >= {"kitchen_light", "bedroom_light"}
    assert {call[1] for call in calls(result)} == {tool}
    assert all(len(process.devices) == 1 for process in result.processes)


def test_a_listed_name_takes_the_command_with_its_arguments(matcher: IntentMatcher) -> None:
    result = matcher.match("Set the kitchen light to 30 percent and the bedroom light")
    assert calls(result) == [
        ("kitchen_light", "set_brightness", {"brightness": 30}),
        ("bedroom_light", "set_brightness", {"brightness": 30}),
    ]


@pytest.mark.parametrize("sentence", ["the kitchen light", "kitchen light", "please the kitchen light"])
def test_a_lone_device_name_actuates_nothing(matcher: IntentMatcher, sentence: str) -> None:
    # Home Assistant's bare "{name}" templates (for scenes) would read it as "turn it on".
    assert matcher.match(sentence).processes == ()


# Media (the speaker stands in for the coming Spotify driver: its intents need no engine change)


@pytest.mark.parametrize(
    ("sentence", "call"),
    [
        ("Pause the music", ("speaker", "pause", {})),
        ("Set the volume to 70", ("speaker", "set_volume", {"volume": 70})),
        ("Skip to the next song", ("speaker", "next_track", {})),
        ("Play Clair de Lune", ("speaker", "play", {"query": "Clair de Lune"})),
        ("turn the volume up", ("speaker", "adjust_volume", {"change": 10})),
    ],
)
def test_ha_media_intents_reach_the_only_media_player(
    matcher: IntentMatcher, sentence: str, call: tuple[str, str, dict[str, Any]]
) -> None:
    assert calls(matcher.match(sentence)) == [call]


def test_media_commands_ask_which_player_when_there_are_two() -> None:
    two = IntentMatcher([speaker("kitchen_speaker"), speaker("desk_speaker")], "en")
    assert two.match("Pause the music").kind == "clarify"


# French: HA's templates, areas in the user's language


def test_french_turns_on_the_kitchen_light_by_its_configured_area(matcher_fr: IntentMatcher) -> None:
    assert calls(matcher_fr.match("allume la lumière de la cuisine")) == [("kitchen_light", "turn_on", {})]


def test_french_replies_are_french(matcher_fr: IntentMatcher) -> None:
    [process] = matcher_fr.match("règle le plafonnier à 20 %").processes
    assert process.plan.steps[0].args == {"brightness": 20}
    assert process.plan.reply.startswith("C'est fait")


def test_french_all_lights_and_ambiguity(matcher_fr: IntentMatcher) -> None:
    assert len(matcher_fr.match("éteins toutes les lumières").processes) == 3
    assert matcher_fr.match("éteins la lumière").kind == "clarify"


def test_a_driver_translation_file_is_used_in_its_language(
    matcher_fr: IntentMatcher, matcher: IntentMatcher
) -> None:
    assert calls(matcher_fr.match("bascule le plafonnier")) == [("kitchen_light", "toggle", {})]
    assert matcher.match("bascule le plafonnier").kind == "no_match"


# Answering "which one?"


def test_an_answer_to_which_one_completes_the_question(matcher: IntentMatcher) -> None:
    result = matcher.follow_up("Turn off the light", "the kitchen one")
    assert result is not None
    assert calls(result) == [("kitchen_light", "turn_off", {})]


def test_a_new_command_is_not_taken_for_an_answer(matcher: IntentMatcher) -> None:
    assert matcher.follow_up("Turn off the light", "Is the kitchen light on?") is None
    assert matcher.follow_up("Turn off the light", "play some jazz") is None


# The task a process receives


def test_the_task_reads_as_a_sentence_and_the_plan_rides_beside_it(matcher: IntentMatcher) -> None:
    [process] = matcher.match("Turn on the kitchen light").processes
    args = process.launch_args
    assert args["task"] == "Turn on the kitchen light."
    assert args["devices"] == ["kitchen_light"]
    assert args["plan"]["steps"] == [{"device": "kitchen_light", "tool": "turn_on", "args": {}}]
    assert process.plan.ack == "On it: turn on the kitchen light."


def test_a_world_without_intents_matches_nothing() -> None:
    bare = IntentMatcher([DeviceVocabulary(name="robot", driver="ros")], "en")
    assert bare.match("Turn on the lamp").kind == "no_match"


@pytest.mark.parametrize(
    ("sentence", "value"),
    [
        ("set the kitchen light to -5 percent", "-5"),
        ("set the kitchen light to minus 5 percent", "minus 5"),
        ("set the living room lamp to 150 percent", "150"),
    ],
)
def test_a_number_no_template_takes_is_refused_naming_it(
    matcher: IntentMatcher, sentence: str, value: str
) -> None:
    result = matcher.match(sentence)
    assert (result.kind, result.processes) == ("no_match", ())
    assert result.reply.startswith(f"I can't do that: {value} is not a value the ")
    assert "Nothing was changed." in result.reply


def test_an_unknown_device_with_a_good_number_is_still_unknown(matcher: IntentMatcher) -> None:
    result = matcher.match("set the garage light to 50 percent")
    assert "garage light" in result.reply and "is not a value" not in result.reply
