"""The ``homeassistant:`` table of an intents.yaml: HA intents onto a driver's tools."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from rosaos.intents.grammar.ha_intents import load_ha_intents, plain_text, state_word
from rosaos.intents.grammar.ha_mapping import HaAction
from rosaos.intents.grammar.intents_file import IntentsFileError, load_intents_file

FILE = """
intents:
  LampOn:
    data: [{sentences: ["turn on [the] {device}"]}]
    tool: turn_on
homeassistant:
  domain: light
  intents:
    HassTurnOn: {tool: turn_on}
    HassLightSet:
      - {tool: set_brightness, args: {brightness: "{brightness}"}}
      - {tool: set_color_name, args: {name: "{color}"}}
    HassGetState: {tool: get_state, states: {"on": {"on": true}}}
"""


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "intents.yaml"
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def test_the_mapping_is_read_and_kept_out_of_the_hassil_part(tmp_path: Path) -> None:
    loaded = load_intents_file(write(tmp_path, FILE))
    assert "homeassistant" not in loaded.hassil
    mapping = loaded.homeassistant
    assert mapping is not None
    assert mapping.domain == "light"
    assert [action.tool for action in mapping.intents["HassLightSet"].actions] == [
        "set_brightness",
        "set_color_name",
    ]
    assert mapping.intents["HassGetState"].states == {"on": {"on": True}}


def test_a_file_without_the_table_has_no_mapping(tmp_path: Path) -> None:
    assert load_intents_file(write(tmp_path, FILE.split("homeassistant:")[0])).homeassistant is None


@pytest.mark.parametrize(
    ("table", "message"),
    [
        (
            "homeassistant: {domain: light, intents: {TurnOn: {tool: turn_on}}}",
            "not Home Assistant intent names",
        ),
        ("homeassistant: {domain: light, intents: {HassTurnOn: {args: {}}}}", "homeassistant"),
        ("homeassistant: {intents: {HassTurnOn: {tool: turn_on}}}", "domain"),
    ],
)
def test_a_bad_table_names_the_file_and_the_problem(tmp_path: Path, table: str, message: str) -> None:
    with pytest.raises(IntentsFileError, match=message):
        load_intents_file(write(tmp_path, FILE.split("homeassistant:")[0] + table))


def test_an_action_applies_when_its_slots_and_conditions_were_heard() -> None:
    brightness = HaAction(tool="set_brightness", args={"brightness": "{brightness}"})
    louder = HaAction(tool="adjust_volume", args={"change": 10}, when={"volume_step": "up"})
    assert brightness.applies({"brightness": 20})
    assert not brightness.applies({"color": "red"})
    assert brightness.fill({"brightness": 20}) == {"brightness": 20}
    assert louder.applies({"volume_step": "up"})
    assert not louder.applies({"volume_step": "down"})


def test_ha_templates_are_cut_down_to_the_mapped_intents_and_domains() -> None:
    intents = load_ha_intents("en", ["HassTurnOn", "HassNotAnIntent"], ["light"])
    assert intents is not None
    assert set(intents.intents) == {"HassTurnOn"}
    domains = {block.slots.get("domain") for block in intents.intents["HassTurnOn"].data} - {None}
    assert domains == {"light"}  # no covers, fans or scenes


def test_no_mapping_or_unknown_language_means_no_ha_templates() -> None:
    assert load_ha_intents("en", [], ["light"]) is None
    assert load_ha_intents("xx-nowhere", ["HassTurnOn"], ["light"]) is None


def test_state_words_come_from_ha_lists_in_the_language() -> None:
    assert state_word("fr", "on_off_states", "off") == "éteint"
    assert plain_text("(cold|cool) white[s]") == "cold white"
