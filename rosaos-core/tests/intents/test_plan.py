"""The plan a task carries: encoded into the task text and read back exactly."""

from __future__ import annotations

import pytest

from rosaos.intents.planning.plan import (
    Plan,
    PlanAnswer,
    PlanError,
    PlanStep,
    decode_plan,
    encode_task,
    fill_state,
    has_plan,
    render_result,
    task_summary,
)

PLAN = Plan(
    steps=[PlanStep(device="kitchen_light", tool="set_brightness", args={"brightness": 20})],
    reply="Done: dim the kitchen light.",
    failure="Sorry: {error}",
    ack="On it.",
)


def test_a_plan_survives_the_round_trip_through_the_task_text() -> None:
    task = encode_task("Set the kitchen light to 20 percent.", PLAN)
    assert decode_plan(task) == PLAN
    assert task_summary(task) == "Set the kitchen light to 20 percent."


def test_a_question_plan_keeps_its_answer_and_unicode() -> None:
    plan = PLAN.model_copy(
        update={"answer": PlanAnswer(when={"on": True}, yes="Oui, allumée.", no="Non, éteinte.")}
    )
    task = encode_task("La lumière est-elle allumée ?", plan)
    assert "éteinte" in task  # readable, not \\u-escaped
    assert decode_plan(task) == plan


def test_a_task_without_a_block_has_no_plan() -> None:
    assert decode_plan("Turn on the kitchen light.") is None
    assert not has_plan("Turn on the kitchen light.")


@pytest.mark.parametrize("body", ["not json", '{"steps": []}', '{"steps": [{"tool": "x"}], "reply": "r"}'])
def test_a_broken_block_is_an_error_that_says_so(body: str) -> None:
    with pytest.raises(PlanError, match="not a valid plan"):
        decode_plan(f"Do it.\n```rosaos-plan\n{body}\n```")


def test_devices_are_listed_once_in_order_of_use() -> None:
    steps = [PlanStep(device=name, tool="t") for name in ("b", "a", "b")]
    assert Plan(steps=steps, reply="r").devices == ["b", "a"]


def test_a_result_renders_on_one_line() -> None:
    assert (
        render_result({"on": False, "brightness": 100, "name": "lamp"})
        == "on: false, brightness: 100, name: lamp"
    )
    assert render_result("ok") == "ok"


def test_state_fields_fill_with_their_format() -> None:
    state = {"track": "So What", "artist": "Miles Davis", "battery": 0.874, "on": True}
    assert fill_state("Playing {track} by {artist}.", state) == "Playing So What by Miles Davis."
    assert fill_state("Battery at {battery:.0%}.", state) == "Battery at 87%."
    assert fill_state("State: {result}", {"on": True}) == "State: on: true"


@pytest.mark.parametrize(
    ("text", "state"),
    [("{battery:.0%}", {"x": 1}), ("{track}", {"track": None}), ("{x:.1f}", {"x": "far"}), ("{x}", [1])],
    ids=["missing", "null", "bad format", "not a mapping"],
)
def test_a_field_that_cannot_be_filled_fills_nothing(text: str, state: object) -> None:
    assert fill_state(text, state) is None
