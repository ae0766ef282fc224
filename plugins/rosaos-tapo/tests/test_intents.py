"""intents.yaml: the offline engine's sentence templates for the bulb, read by core's loader."""

from __future__ import annotations

from typing import Any

import pytest

from rosaos.intents.grammar.intents_file import IntentsFile
from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.testing import IntentProbe
from rosaos_tapo.colors import NAMED_COLORS
from rosaos_tapo.plugin import SPEC


@pytest.fixture(scope="module")
def probe() -> IntentProbe:
    """The templates, with three bulbs in the {device} list."""
    return IntentProbe(
        SPEC,
        devices={
            "kitchen light": "kitchen_light",
            "living room lamp": "living_room_lamp",
            "bedroom light": "bedroom_light",
        },
    )


@pytest.fixture(scope="module")
def intents_file(probe: IntentProbe) -> IntentsFile:
    return probe.intents_file


@pytest.mark.parametrize(
    ("sentence", "expected"),
    [
        # The light tasks of the bench (../shared/bench/tasks/home.yaml), one device each.
        ("Turn on the kitchen light", ("kitchen_light", "turn_on", {})),
        ("Switch off the living room lamp", ("living_room_lamp", "turn_off", {})),
        (
            "Set the living room lamp to 20 percent",
            ("living_room_lamp", "set_brightness", {"brightness": 20}),
        ),
        ("Make the bedroom light green", ("bedroom_light", "set_color_name", {"name": "green"})),
        ("Set the kitchen light to warm white", ("kitchen_light", "set_color_name", {"name": "warm white"})),
        ("Dim the living room lamp", ("living_room_lamp", "adjust_brightness", {"change": -25})),
        ("Toggle the bedroom light", ("bedroom_light", "toggle", {})),
        # Other phrasings the templates cover.
        ("turn the kitchen light off", ("kitchen_light", "turn_off", {})),
        ("set the kitchen light to 35%", ("kitchen_light", "set_brightness", {"brightness": 35})),
        ("make the bedroom light brighter", ("bedroom_light", "adjust_brightness", {"change": 25})),
        (
            "set the colour of the kitchen light to sky blue",
            ("kitchen_light", "set_color_name", {"name": "sky blue"}),
        ),
        ("set the kitchen light to 3000 kelvin", ("kitchen_light", "set_color_temp", {"kelvin": 3000})),
    ],
)
def test_sentence_maps_to_tool_call(
    probe: IntentProbe, sentence: str, expected: tuple[str, str, dict[str, Any]]
) -> None:
    assert probe.match(sentence) == expected


@pytest.mark.parametrize(
    "sentence", ["Turn off the light", "Turn on the garage light", "Is the kitchen light on?"]
)
def test_ambiguous_unknown_or_question_sentences_do_not_match(probe: IntentProbe, sentence: str) -> None:
    # bench: these must change nothing, so the offline engine must not act on them.
    assert probe.match(sentence) is None


def test_color_list_holds_exactly_the_named_colours(intents_file: IntentsFile) -> None:
    values = [
        value if isinstance(value, str) else value["in"]
        for value in intents_file.hassil["lists"]["color"]["values"]
    ]
    assert values == list(NAMED_COLORS)


UNNAMED_NEEDS = {"TapoNeedLight"}
"""Intents that may name no bulb: "it's too dark in here" needs light wherever the user is."""


def test_every_intent_template_names_its_target(intents_file: IntentsFile) -> None:
    # A bulb is never "the only one" by default: a template names the device, its area, or all;
    # only a need for light may name none (then the only bulb, or the engine asks which).
    for name, intent in intents_file.hassil["intents"].items():
        every = intents_file.actions[name].every
        for data in intent["data"]:
            for sentence in data["sentences"]:
                named = "{device}" in sentence or "{area}" in sentence or (every and "{every}" in sentence)
                assert named or name in UNNAMED_NEEDS, f"{name}: {sentence!r} names no device"


@pytest.mark.parametrize(
    "sentence",
    ["I can't see a thing in here", "it's too dark in here", "it's pitch black", "I can't see anything"],
)
def test_a_need_for_light_with_no_place_lights_the_only_bulb_or_asks_which(sentence: str) -> None:
    assert SPEC.intents is not None
    kitchen = DeviceVocabulary("kitchen_light", "tapo", "Ceiling light in the kitchen", intents=SPEC.intents)
    bedroom = DeviceVocabulary("bedroom_light", "tapo", "Bedside light in the bedroom", intents=SPEC.intents)
    alone = IntentMatcher([kitchen], "en").match(sentence)
    assert [(s.device, s.tool) for p in alone.processes for s in p.plan.steps] == [
        ("kitchen_light", "turn_on")
    ]
    both = IntentMatcher([kitchen, bedroom], "en").match(sentence)
    assert both.kind == "clarify" and not both.processes
    assert "kitchen light" in both.reply and "bedroom light" in both.reply


# The homeassistant: table — Home Assistant's multilingual intents mapped onto the bulb's tools


def test_the_bulb_behaves_like_an_ha_light(intents_file: IntentsFile) -> None:
    mapping = intents_file.homeassistant
    assert mapping is not None
    assert mapping.domain == "light"
    assert {"HassTurnOn", "HassTurnOff", "HassLightSet", "HassGetState"} <= set(mapping.intents)


async def test_every_ha_action_calls_a_bulb_tool_with_arguments_it_takes(
    intents_file: IntentsFile, open_bulb: Any
) -> None:
    async with open_bulb() as bulb:
        tools = {tool.name: tool for tool in await bulb.client.list_tools()}
    assert intents_file.homeassistant is not None
    for intent, mapping in intents_file.homeassistant.intents.items():
        for action in mapping.actions:
            assert action.tool in tools, f"{intent}: no tool {action.tool}"
            accepted = set(tools[action.tool].input_schema.get("properties") or {})
            assert set(action.args) <= accepted, f"{intent}: {action.tool} takes {sorted(accepted)}"


def test_ha_state_answers_use_get_state_keys(intents_file: IntentsFile) -> None:
    assert intents_file.homeassistant is not None
    states = intents_file.homeassistant.intents["HassGetState"].states
    assert states == {"on": {"on": True}, "off": {"on": False}}


@pytest.mark.parametrize(
    ("language", "sentence", "expected"),
    [
        (
            "en",
            "Turn off all the lights",
            [("kitchen_light", "turn_off", {}), ("bedroom_light", "turn_off", {})],
        ),
        (
            "en",
            "set the kitchen light color temperature to warm white",
            [("kitchen_light", "set_color_temp", {"kelvin": 2700})],
        ),
        ("fr", "allume la lumière de la cuisine", [("kitchen_light", "turn_on", {})]),
        (
            "fr",
            "mets la lumière de la chambre en bleu",
            [("bedroom_light", "set_color_name", {"name": "blue"})],
        ),
    ],
)
def test_ha_sentences_reach_the_bulbs_through_the_engine(
    language: str, sentence: str, expected: list[tuple[str, str, dict[str, Any]]]
) -> None:
    assert SPEC.intents is not None
    world = [
        DeviceVocabulary(
            "kitchen_light", "tapo", "Ceiling light in the kitchen", area="cuisine", intents=SPEC.intents
        ),
        DeviceVocabulary(
            "bedroom_light", "tapo", "Bedside light in the bedroom", area="chambre", intents=SPEC.intents
        ),
    ]
    result = IntentMatcher(world, language).match(sentence)
    planned = [
        (step.device, step.tool, step.args) for process in result.processes for step in process.plan.steps
    ]
    assert planned == expected


@pytest.mark.parametrize(
    "sentence", ["How bright is the kitchen light?", "what's the brightness of the bedroom light"]
)
def test_a_brightness_question_reads_the_state(probe: IntentProbe, sentence: str) -> None:
    match = probe.match(sentence)
    assert match is not None and (match.tool, match.args) == ("get_state", {})


@pytest.mark.parametrize(
    ("sentence", "expected"),
    [
        ("Switch the kitchen light to blue", ("kitchen_light", "set_color_name", {"name": "blue"})),
        (
            "Set the kitchen light to full brightness",
            ("kitchen_light", "set_brightness", {"brightness": 100}),
        ),
        ("turn the bedroom light all the way up", ("bedroom_light", "set_brightness", {"brightness": 100})),
    ],
)
def test_everyday_variants(
    probe: IntentProbe, sentence: str, expected: tuple[str, str, dict[str, int | str]]
) -> None:
    assert probe.match(sentence) == expected
