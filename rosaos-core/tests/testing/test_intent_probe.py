"""IntentProbe (rosaos.testing.intents): a sentence in, the tool call the offline engine makes out."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from rosaos.drivers import DriverSpec
from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.testing import IntentMatch, IntentProbe

INTENTS = """
language: en
intents:
  LampTurnOn:
    data:
      - sentences: ["turn on [the] {device}", "switch [the] {device} on"]
    tool: turn_on
  LampSetLevel:
    data:
      - sentences: ["set [the] {device} to {level}[ ][%|percent]"]
    tool: set_level
    args: {level: "{level}", fade: true}
  LampDim:
    data:
      - sentences: ["dim [the] {device}"]
    tool: adjust_level
    args: {change: -25}
  LampBlink:
    data:
      - sentences: ["blink [the] {device}", "blink [the] {device} {times} times"]
    tool: blink
    args: {times: "{times}"}
  LampSay:
    data:
      - sentences: ["{device} say {text}"]
    tool: say
    args: {text: "{text}"}
  LampGreet:
    data:
      - sentences: ["{device} say hello"]
    tool: greet
  LampsOut:
    data:
      - sentences: ["lights out"]
    tool: turn_off
lists:
  level:
    range: {from: 0, to: 100, multiplier: 1.0}
  times:
    range: {from: 1, to: 10}
  text:
    wildcard: true
"""

FRENCH = """
language: fr
intents:
  LampTurnOn:
    data:
      - sentences: ["allume [la] {device}"]
    tool: turn_on
"""

DEVICES = {"ceiling light": "kitchen_light", "bedside lamp": "bedroom_light", "light": "kitchen_light"}


@pytest.fixture
def intents(tmp_path: Path) -> Path:
    path = tmp_path / "intents.yaml"
    path.write_text(INTENTS, encoding="utf-8")
    return path


@pytest.fixture
def probe(intents: Path) -> IntentProbe:
    return IntentProbe(intents, devices=DEVICES)


def engine_call(world: list[DeviceVocabulary], sentence: str) -> tuple[str, str, dict[str, Any]] | None:
    """The one tool call the real engine plans for ``sentence``, or None."""
    steps = [
        step for process in IntentMatcher(world).match(sentence).processes for step in process.plan.steps
    ]
    return (steps[0].device, steps[0].tool, steps[0].args) if len(steps) == 1 else None


def test_a_sentence_gives_the_device_the_tool_and_the_filled_arguments(probe: IntentProbe) -> None:
    assert probe.match("set the ceiling light to 40 percent") == IntentMatch(
        "kitchen_light", "set_level", {"level": 40, "fade": True}
    )


def test_whole_numbers_are_passed_as_int_as_the_engine_does(probe: IntentProbe) -> None:
    match = probe.match("set the ceiling light to 40%")
    assert match is not None
    assert type(match.args["level"]) is int


def test_literal_arguments_are_passed_as_written(probe: IntentProbe) -> None:
    assert probe.match("dim the bedside lamp") == ("bedroom_light", "adjust_level", {"change": -25})


def test_every_instance_answers_to_its_own_name_spoken(probe: IntentProbe) -> None:
    assert probe.match("switch the bedroom light on") == ("bedroom_light", "turn_on", {})


def test_the_most_literal_template_wins_over_a_wildcard(probe: IntentProbe) -> None:
    assert probe.match("light say hello") == ("kitchen_light", "greet", {})
    assert probe.match("light say good night") == ("kitchen_light", "say", {"text": "good night"})


@pytest.mark.parametrize(
    "sentence",
    [
        "turn on the garage light",  # no such device
        "make me a sandwich",  # no template
        "blink the light",  # the {times} argument gets no value
    ],
)
def test_the_engine_would_not_act(probe: IntentProbe, sentence: str) -> None:
    assert probe.match(sentence) is None


def test_a_template_without_device_means_the_only_instance(intents: Path) -> None:
    assert IntentProbe(intents, devices={"lamp": "lamp"}).match("lights out") == ("lamp", "turn_off", {})


def test_a_template_without_device_is_no_call_when_there_are_several(probe: IntentProbe) -> None:
    assert probe.match("lights out") is None  # the engine asks which one


@pytest.mark.parametrize(
    "sentence",
    [
        "set the ceiling light to 40 percent",
        "switch the bedroom light on",
        "dim the light",
        "light say hello",
        "bedside lamp say good night",
        "blink the light 3 times",
        "blink the light",
        "lights out",
        "turn on the garage light",
    ],
)
def test_the_probe_agrees_with_the_engine(intents: Path, probe: IntentProbe, sentence: str) -> None:
    aliases: dict[str, list[str]] = {}
    for spoken, instance in DEVICES.items():
        aliases.setdefault(instance, []).append(spoken)
    world = [
        DeviceVocabulary(name, "lamp", aliases=tuple(names), intents=intents)
        for name, names in aliases.items()
    ]
    assert probe.match(sentence) == engine_call(world, sentence)


def test_a_language_reads_the_translated_file_next_to_it(intents: Path) -> None:
    intents.with_name("intents.fr.yaml").write_text(FRENCH, encoding="utf-8")
    probe = IntentProbe(intents, devices={"lampe": "lamp"}, language="fr")
    assert probe.match("allume la lampe") == ("lamp", "turn_on", {})


def test_a_language_without_a_file_is_refused(intents: Path) -> None:
    with pytest.raises(ValueError, match=r"intents\.de\.yaml"):
        IntentProbe(intents, devices=DEVICES, language="de")


def test_a_driver_spec_is_read_through_its_intents_file(intents: Path) -> None:
    spec = driver_spec(intents=intents)
    assert IntentProbe(spec, devices={"lamp": "lamp"}).match("dim the lamp") == (
        "lamp",
        "adjust_level",
        {"change": -25},
    )


def test_a_driver_without_intents_is_refused() -> None:
    with pytest.raises(ValueError, match="ships no intents file"):
        IntentProbe(driver_spec(intents=None), devices={"lamp": "lamp"})


def driver_spec(intents: Path | None) -> DriverSpec:
    return DriverSpec(
        name="lamp",
        title="Lamp",
        description="A lamp.",
        concurrency="exclusive",
        prompt="You control a lamp.",
        server=lambda ctx, backend: None,
        backends={"sim": lambda ctx: None},
        intents=intents,
    )
