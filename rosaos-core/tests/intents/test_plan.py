"""The plan a process carries: a typed field of the launch, the job and the callback; rendered only for an LLM."""

from __future__ import annotations

import pytest

from rosaos.events.plan import Plan, PlanAnswer, PlanStep, fill_state, launch_args, plan_text, render_result

PLAN = Plan(
    steps=[PlanStep(device="kitchen_light", tool="set_brightness", args={"brightness": 20})],
    reply="Done: dim the kitchen light.",
    failure="Sorry: {error}",
    ack="On it.",
)


def test_the_launch_carries_the_words_as_the_task_and_the_plan_as_data() -> None:
    args = launch_args(" Set the kitchen light to 20 percent. ", ["kitchen_light"], PLAN)
    assert args["task"] == "Set the kitchen light to 20 percent."
    assert args["devices"] == ["kitchen_light"]
    assert Plan.model_validate(args["plan"]) == PLAN  # JSON data in the tool call, validated by the tool


def test_a_question_plan_keeps_its_answer_and_unicode_for_an_llm_to_read() -> None:
    plan = PLAN.model_copy(
        update={"answer": PlanAnswer(when={"on": True}, yes="Oui, allumée.", no="Non, éteinte.")}
    )
    text = plan_text(plan)
    assert "éteinte" in text  # readable, not \\u-escaped
    assert Plan.model_validate(launch_args("La lumière est-elle allumée ?", ["lamp"], plan)["plan"]) == plan


@pytest.mark.parametrize("data", [{}, {"steps": []}, {"steps": [{"tool": "x"}], "reply": "r"}])
def test_a_broken_plan_is_refused_by_validation(data: dict[str, object]) -> None:
    with pytest.raises(ValueError, match="validation error"):
        Plan.model_validate(data)


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
