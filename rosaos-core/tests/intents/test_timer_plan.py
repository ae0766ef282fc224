"""The offline kernel model sets, lists and cancels real timers, and carries out a fired one."""

from __future__ import annotations

from collections.abc import AsyncIterator
from datetime import UTC, datetime, timedelta
from pathlib import Path
from typing import Any

import pytest
from fastmcp import FastMCP

from rosaos.events.plan import Plan
from rosaos.kernel.event_store import EventStore
from rosaos.models.kernel_model import LocalIntentModel
from rosaos.timers.timer_book import TimerBook, fired_event
from rosaos.timers.timer_tools import add_timer_tools

from .engine_turns import EngineKernel, event, said
from .intents_support import home_world


class TimerKernel(EngineKernel):
    """The offline engine with real timer tools and a recording launch_process."""

    def __init__(self, model: LocalIntentModel, book: TimerBook) -> None:
        tools = FastMCP("kernel-tools")
        add_timer_tools(tools, book)
        super().__init__(model, tools)
        self.book = book
        self.launched: list[tuple[str, list[str], Plan | None]] = []

        @tools.tool
        async def launch_process(task: str, devices: list[str], plan: Plan | None = None) -> dict[str, Any]:
            """Start a process."""
            self.launched.append((task, devices, plan))
            return {"process_id": len(self.launched), "devices": devices, "state": "running"}


@pytest.fixture(scope="module")
def model() -> LocalIntentModel:
    return LocalIntentModel(home_world(), language="en")


@pytest.fixture
async def kernel(model: LocalIntentModel, tmp_path: Path) -> AsyncIterator[TimerKernel]:
    store = await EventStore.open(tmp_path / "kernel.sqlite3")
    book = await TimerBook.open(store)
    yield TimerKernel(model, book)
    await store.close()


async def test_a_relative_timer_is_stored_and_nothing_runs_now(kernel: TimerKernel) -> None:
    before = datetime.now(UTC)
    reply = await kernel.say("turn off the kitchen light in ten minutes")
    [timer] = await kernel.book.pending()
    assert timer.action == "turn off the kitchen light"
    assert timedelta(seconds=599) <= timer.due - before <= timedelta(seconds=602)
    assert kernel.launched == []
    assert reply.startswith(f"Timer {timer.id} set: turn off the kitchen light at ")
    assert "(in 10 minutes)" in reply


async def test_a_clock_time_in_words_is_the_next_such_local_time(kernel: TimerKernel) -> None:
    await kernel.say("Stop the music at eleven thirty p.m.")
    [timer] = await kernel.book.pending()
    local = timer.due.astimezone()
    assert (local.hour, local.minute) == (23, 30)
    assert timedelta(0) < timer.due - datetime.now(UTC) <= timedelta(days=1)
    assert "music" in timer.action


async def test_listing_and_cancelling_that_timer(kernel: TimerKernel) -> None:
    await kernel.say("turn on the bedroom light in 2 hours")
    await kernel.say("in 5 minutes, turn off the living room lamp")
    listing = await kernel.say("what timers are set?")
    assert listing.startswith("2 timers: ")
    assert listing.index("turn off the living room lamp") < listing.index("turn on the bedroom light")

    cancelled = await kernel.say("cancel that timer")
    assert "turn off the living room lamp" in cancelled  # the newest one
    assert [timer.action for timer in await kernel.book.pending()] == ["turn on the bedroom light"]
    assert (await kernel.say("cancel the bedroom timer")).startswith("Cancelled timer")
    assert await kernel.book.pending() == []
    assert await kernel.say("any timers?") == "No timers are set."
    assert "nothing to cancel" in await kernel.say("cancel the timer")


async def test_a_timer_for_an_unknown_device_is_refused_with_the_reason(kernel: TimerKernel) -> None:
    reply = await kernel.say("turn on the garage door in ten minutes")
    assert reply.startswith("I can't set a timer for that:")
    assert await kernel.book.pending() == []


async def test_an_ambiguous_timer_asks_for_the_whole_timer_again(kernel: TimerKernel) -> None:
    reply = await kernel.say("turn off the light in ten minutes")
    assert reply.startswith("Which one do you mean:") and reply.endswith("say the timer again with the name.")
    assert await kernel.book.pending() == []


async def test_a_fired_timer_launches_its_action_and_says_how_late(kernel: TimerKernel) -> None:
    timer = await kernel.book.set("turn off the kitchen light", datetime.now(UTC) - timedelta(hours=2))
    fired = fired_event(timer, datetime.now(UTC)).payload
    reply = await kernel.say(event("timer_fired", fired))  # typed, as the kernel loop hands it over
    [(_, devices, plan)] = kernel.launched
    assert devices == ["kitchen_light"]
    assert plan is not None and plan.steps[0].tool == "turn_off"
    assert reply.startswith(f"Timer {timer.id} (2 hours late")


def test_prefer_local_takes_timer_sentences_it_understands_completely(model: LocalIntentModel) -> None:
    assert model.handles_event(said("turn off the kitchen light in ten minutes"))
    assert model.handles_event(said("what timers are set?"))
    assert not model.handles_event(said("turn on the garage door in ten minutes"))
    assert not model.handles_event(said("remind me about the oven at some point"))
