"""Confirmation rules, answers and the desk's timeout (the end-to-end flow is in tests/)."""

from __future__ import annotations

import asyncio

import pytest

from rosaos.confirmations.confirmation_desk import (
    ConfirmationDesk,
    ConfirmationRequest,
    question,
    read_answer,
)
from rosaos.confirmations.confirming import confirm_rule, needs_confirmation


def test_real_ros_robots_confirm_destructive_tools_by_default_and_sims_do_not() -> None:
    assert confirm_rule(None, None, "real", on_real=True) == "destructive"
    assert confirm_rule(None, None, "sim", on_real=True) is None
    assert confirm_rule(None, None, "real", on_real=False) is None
    assert confirm_rule("off", None, "real", on_real=True) is None
    assert confirm_rule(None, "destructive", "sim", on_real=False) == "destructive"
    assert confirm_rule(["drive"], "off", "sim", on_real=False) == ["drive"]


def test_destructive_means_the_annotation() -> None:
    assert needs_confirmation("destructive", "drive", {"destructiveHint": True})
    assert not needs_confirmation("destructive", "get_state", {"readOnlyHint": True})
    assert needs_confirmation(["send_goal"], "send_goal", None)
    assert not needs_confirmation(None, "drive", {"destructiveHint": True})


def test_answers_and_questions_read_naturally() -> None:
    assert [read_answer(t) for t in ("Yes.", "go ahead", "ok do it", "No!", "cancel that", "what?")] == [
        "yes",
        "yes",
        "yes",
        "no",
        "no",
        None,
    ]
    assert question("turtlebot", "move_distance", {"meters": 2}) == (
        "The turtlebot will move distance (meters 2). Go ahead?"
    )


async def test_silence_expires_a_question_and_a_late_answer_is_refused() -> None:
    desk = ConfirmationDesk(timeout=0.2)
    item = await desk.ask(ConfirmationRequest(process_id=1, device="turtlebot", tool="drive"))
    assert (await desk.wait(item.id, 0.01)).state == "pending"
    assert (await desk.wait(item.id, 2)).state == "expired"
    with pytest.raises(ValueError, match="already expired"):
        desk.answer(item.id, "yes", by="api")
    assert desk.pending() == [] and desk.answer_oldest("yes", by="cli") is None


async def test_a_yes_answers_the_oldest_pending_question() -> None:
    desk = ConfirmationDesk(timeout=5)
    first = await desk.ask(ConfirmationRequest(process_id=1, device="turtlebot", tool="drive"))
    second = await desk.ask(ConfirmationRequest(process_id=2, device="turtlebot", tool="rotate"))
    waiting = asyncio.create_task(desk.wait(first.id, 5))
    answered = desk.answer_oldest("yes please", by="web")
    assert answered is not None and answered.id == first.id and (await waiting).state == "yes"
    assert [item.id for item in desk.pending()] == [second.id]
