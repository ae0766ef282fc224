"""A driver's intents.yaml (rosaos.intents.grammar.intents_file): hassil sentences plus the tool each intent calls."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest
from hassil import recognize

from rosaos.intents.grammar.intents_file import IntentAction, IntentsFileError, load_intents_file

INLINE = """
language: en
intents:
  LampSetBrightness:
    data:
      - sentences: ["set [the] lamp to {brightness}[ ][%|percent]"]
    tool: set_brightness
    args: {brightness: "{brightness}"}
  LampDim:
    data:
      - sentences: ["dim [the] lamp"]
    tool: adjust_brightness
    args: {change: -25}
lists:
  brightness:
    range: {from: 0, to: 100}
"""


def intents_file(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "intents.yaml"
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def test_inline_tool_and_args_are_read_next_to_data(tmp_path: Path) -> None:
    loaded = load_intents_file(intents_file(tmp_path, INLINE))
    assert loaded.actions == {
        "LampSetBrightness": IntentAction(tool="set_brightness", args={"brightness": "{brightness}"}),
        "LampDim": IntentAction(tool="adjust_brightness", args={"change": -25}),
    }


def test_the_hassil_part_has_no_rosaos_keys_and_recognises_sentences(tmp_path: Path) -> None:
    loaded = load_intents_file(intents_file(tmp_path, INLINE))
    assert set(loaded.hassil["intents"]["LampDim"]) == {"data"}
    match = recognize("set the lamp to 40 percent", loaded.intents())
    assert match is not None
    assert (match.intent.name, match.entities["brightness"].value) == ("LampSetBrightness", 40)


def test_a_top_level_rosaos_table_maps_intents_to_tools(tmp_path: Path) -> None:
    text = """
    intents:
      LampOn:
        data: [{sentences: ["turn on [the] lamp"]}]
    rosaos:
      LampOn: {tool: turn_on}
    """
    loaded = load_intents_file(intents_file(tmp_path, text))
    assert (loaded.actions, loaded.language, "rosaos" in loaded.hassil) == (
        {"LampOn": IntentAction(tool="turn_on")},
        "en",
        False,
    )


def test_slot_arguments_are_the_ones_written_as_a_slot_reference() -> None:
    action = IntentAction(tool="set_color", args={"name": "{color}", "brightness": 50, "note": "x {y}"})
    assert action.slot_arguments() == {"name": "color"}


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "intents:\n  LampOn:\n    data: [{sentences: [on]}]\n",
            "intents.LampOn: names no tool; add 'tool: <tool name>' next to 'data:'",
        ),
        (
            "intents:\n  LampOn:\n    data: [{sentences: [on]}]\n    tool: turn_on\nrosaos:\n  LampOn: {tool: turn_on}\n",
            "intents.LampOn: tool given both inline and under 'rosaos:'; keep one",
        ),
        (
            "intents:\n  LampOn:\n    data: [{sentences: [on]}]\n    tool: turn_on\nrosaos:\n  LampOff: {tool: turn_off}\n",
            "rosaos: LampOff: no such intent under 'intents:'",
        ),
        (
            "intents:\n  LampOn:\n    data: [{sentences: [on]}]\n    tool: turn_on\n    args: [1, 2]\n",
            "intents.LampOn: args: Input should be a valid dictionary",
        ),
        ("intents:\n  LampOn:\n    tool: turn_on\n", "hassil cannot parse it: KeyError: 'data'"),
        ("language: en\n", "expected a mapping with a non-empty 'intents:' table"),
        ("intents: [unclosed\n", "not valid YAML"),
    ],
    ids=["no tool", "tool twice", "unknown intent", "args not a mapping", "hassil", "no intents", "yaml"],
)
def test_a_bad_file_is_an_error_naming_file_intent_and_fix(tmp_path: Path, text: str, message: str) -> None:
    path = intents_file(tmp_path, text)
    with pytest.raises(IntentsFileError) as raised:
        load_intents_file(path)
    assert str(raised.value).startswith(f"{path}: ")
    assert message in str(raised.value)


QUESTIONS = """
intents:
  LampHowBright:
    data: [{sentences: ["how bright is [the] lamp"]}]
    tool: get_state
    answer:
      when: {"on": true}
      yes: "The {device} is at {brightness}%."
      no: "The {device} is off."
  LampLevel:
    data: [{sentences: ["what is the lamp level"]}]
    tool: get_state
    reply: "Level {brightness}."
"""


def test_a_question_intent_carries_its_answer_or_reply(tmp_path: Path) -> None:
    actions = load_intents_file(intents_file(tmp_path, QUESTIONS)).actions
    answer = actions["LampHowBright"].answer
    assert answer is not None  # unquoted yes:/no: keys (YAML booleans) are read as the words
    assert (answer.when, answer.yes, answer.no) == (
        {"on": True},
        "The {device} is at {brightness}%.",
        "The {device} is off.",
    )
    assert actions["LampLevel"].reply == "Level {brightness}."
    assert actions["LampLevel"].is_question and actions["LampHowBright"].is_question


@pytest.mark.parametrize(
    ("block", "message"),
    [
        ('answer: {when: {on: true}, "yes": "y", "no": "n"}', "quote it"),
        ('answer: {when: {"on": true}, "yes": "y", "no": "n"}\n    reply: "r"', "not both"),
        ('answer: {when: {}, "yes": "y", "no": "n"}', "answer.when"),
    ],
    ids=["unquoted on", "answer and reply", "empty when"],
)
def test_a_bad_question_is_an_error_that_says_how_to_fix_it(tmp_path: Path, block: str, message: str) -> None:
    text = f"intents:\n  Q:\n    data: [{{sentences: [q]}}]\n    tool: get_state\n    {block}\n"
    with pytest.raises(IntentsFileError, match=r"intents\.Q: ") as raised:
        load_intents_file(intents_file(tmp_path, text))
    assert message in str(raised.value)
