"""How a process's end is judged: from its device calls, never from what its model wrote (issue 22)."""

from __future__ import annotations

import pytest

from rosaos.processes.jobs import GrantedDevice
from rosaos.processes.outcome import asks_for_change, judge
from rosaos.processes.tool_calls import ToolCall, ToolCallLog


def device(name: str, tools: list[str] | None = None) -> GrantedDevice:
    return GrantedDevice(
        name=name,
        driver="test",
        url="http://127.0.0.1:1/mcp",
        token="t",
        description="",
        prompt="",
        tools=tools,
    )


LIGHT = device("kitchen_light")
SPEAKER = device("reachy", tools=["speak", "stop_speaking"])
"""The always-attached robot, granted its speaking tools only."""


def log(*calls: tuple[str, str, bool, bool]) -> ToolCallLog:
    """Calls as (device, tool, ok, changes)."""
    return ToolCallLog([ToolCall(d, t, ok, None if ok else "refused", 0.01, ch) for d, t, ok, ch in calls])


@pytest.mark.parametrize(
    "task",
    [
        "Turn on the kitchen light.",
        "Please set the living room lamp's colour to blue.",
        "Undock, then search the environment for a person and report whether you found one.",
        "Check the lamp and then turn it off",
        "Play some jazz.",
    ],
)
def test_commands_ask_for_a_change(task: str) -> None:
    assert asks_for_change(task)


@pytest.mark.parametrize(
    "task",
    [
        "Is the kitchen light on?",
        "Take a picture and tell me what you see.",
        "If the lamp is off, turn it on.",
        "Turn the porch light on when it gets dark",
        "Search the flat for a person.",
        "Report the TurtleBot's battery level.",
    ],
)
def test_questions_looks_and_conditional_changes_do_not(task: str) -> None:
    assert not asks_for_change(task)


def test_the_follow_up_note_after_the_task_is_not_read_as_the_task() -> None:
    task = (
        "Search the flat for a person.\n\nKernel follow-up (launch when this succeeds): Turn the lamp green."
    )
    assert not asks_for_change(task)


def test_a_successful_change_call_ends_ok() -> None:
    calls = log(("kitchen_light", "get_state", True, False), ("kitchen_light", "turn_on", True, True))
    outcome = judge(
        "ok", None, task="Turn on the kitchen light.", devices=[LIGHT], calls=calls, model_ran=True
    )
    assert outcome == ("ok", None)


def test_no_call_at_all_is_unverified() -> None:
    outcome = judge(
        "ok", None, task="Turn on the kitchen light.", devices=[LIGHT], calls=log(), model_ran=True
    )
    assert outcome.status == "unverified"
    assert "made no successful device call" in (outcome.error or "")


def test_an_only_call_that_failed_is_an_error_with_the_devices_words() -> None:
    calls = log(("kitchen_light", "turn_on", False, True))
    outcome = judge(
        "ok", None, task="Turn on the kitchen light.", devices=[LIGHT], calls=calls, model_ran=True
    )
    assert outcome == ("error", "kitchen_light: turn_on failed: refused")


def test_a_failed_call_is_told_in_the_drivers_words_without_fastmcps_head() -> None:
    error = "Error calling tool 'next_track': nothing is loaded, so there is no next track"
    calls = ToolCallLog([ToolCall("spotify", "next_track", False, error, 0.01, True)])
    outcome = judge("ok", None, task="Next song.", devices=[LIGHT], calls=calls, model_ran=False)
    assert outcome == ("error", "spotify: next_track failed: nothing is loaded, so there is no next track")


def test_a_failure_made_good_by_a_retry_of_the_same_tool_ends_ok() -> None:
    calls = log(("kitchen_light", "turn_on", False, True), ("kitchen_light", "turn_on", True, True))
    outcome = judge(
        "ok", None, task="Turn on the kitchen light.", devices=[LIGHT], calls=calls, model_ran=True
    )
    assert outcome == ("ok", None)


def test_a_change_task_whose_calls_only_read_is_unverified() -> None:
    calls = log(("kitchen_light", "get_state", True, False))
    outcome = judge(
        "ok", None, task="Turn on the kitchen light.", devices=[LIGHT], calls=calls, model_ran=True
    )
    assert outcome.status == "unverified"
    assert "only read state (kitchen_light.get_state)" in (outcome.error or "")


def test_speaking_through_the_attached_robot_does_not_prove_the_lights_change() -> None:
    calls = log(("reachy", "speak", True, True))
    outcome = judge(
        "ok", None, task="Turn on the kitchen light.", devices=[LIGHT, SPEAKER], calls=calls, model_ran=True
    )
    assert outcome.status == "unverified"
    assert "made no successful device call" in (outcome.error or "")


def test_a_question_answered_by_reading_ends_ok() -> None:
    calls = log(("kitchen_light", "get_state", True, False))
    outcome = judge("ok", None, task="Is the kitchen light on?", devices=[LIGHT], calls=calls, model_ran=True)
    assert outcome == ("ok", None)


def test_an_offline_plan_run_is_judged_on_failures_only() -> None:
    outcome = judge(
        "ok", None, task="Turn on the kitchen light.", devices=[LIGHT], calls=log(), model_ran=False
    )
    assert outcome == ("ok", None)


def test_an_end_that_is_already_not_ok_is_kept() -> None:
    outcome = judge(
        "timeout",
        "ran past 30 s",
        task="Turn on the kitchen light.",
        devices=[LIGHT],
        calls=log(),
        model_ran=True,
    )
    assert outcome == ("timeout", "ran past 30 s")
