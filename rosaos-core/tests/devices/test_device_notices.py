"""Device notices: the board a driver posts to, ``GET /notices`` over real HTTP, and the kernel's watcher."""

from __future__ import annotations

import asyncio
from typing import Any

import httpx
import pytest
from fastmcp import FastMCP
from pydantic import BaseModel, Field

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.devices.serve import add_notice_route, serve_http
from rosaos.drivers import DeviceContext, DeviceSettings
from rosaos.events.types import DeviceNoticeEvent
from rosaos.notices.notice_board import NoticeBatch, NoticeBoard, NoticeError, NoticeSpec, check_notice_specs
from rosaos.notices.notice_watcher import NoticeFilter, NoticeWatcher, notice_event, notices_url

TOKEN = "notice-token-0123456789"


class Battery(BaseModel):
    battery: float = Field(ge=0, le=1)


SPECS = {
    "battery_low": NoticeSpec(
        description="Battery under 20 %", importance="notify", data=Battery, example={"battery": 0.12}
    ),
    "docked": NoticeSpec(description="Back on the dock"),
}


def board() -> NoticeBoard:
    return NoticeBoard("turtlebot", "ros", SPECS)


def test_a_declared_notice_is_posted_with_its_default_importance() -> None:
    notice = board().post("battery_low", {"battery": 0.12}, message="turtlebot: battery at 12 %")
    assert (notice.seq, notice.device, notice.driver, notice.importance) == (1, "turtlebot", "ros", "notify")
    assert notice.data == {"battery": 0.12}


def test_an_undeclared_notice_is_refused_naming_the_declared_ones() -> None:
    with pytest.raises(NoticeError, match="declared: battery_low, docked"):
        board().post("on_fire")


def test_data_that_breaks_the_model_is_refused() -> None:
    with pytest.raises(NoticeError, match="battery"):
        board().post("battery_low", {"battery": 7})
    with pytest.raises(NoticeError, match="declares no data"):
        board().post("docked", {"where": "dock"})


def test_the_context_posts_to_its_board() -> None:
    ctx = DeviceContext("turtlebot", "TurtleBot", DeviceSettings(), "sim", notices=board())
    ctx.notify("docked", importance="notify")
    assert [(n.name, n.importance, n.message) for n in ctx.notices.after(0).notices] == [
        ("docked", "notify", "turtlebot: docked")
    ]


def test_a_new_board_life_resends_what_it_kept() -> None:
    notices = board()
    notices.post("docked")
    assert notices.after(1).notices == []
    assert [n.seq for n in notices.after(1, board="0ldb0a4d").notices] == [1]


def test_check_notice_specs_reports_a_broken_example() -> None:
    broken = {"battery_low": NoticeSpec(description="low", data=Battery, example={"battery": "lots"})}
    assert check_notice_specs(SPECS) == []
    assert "example does not validate" in check_notice_specs(broken)[0]


def test_the_filter_drops_repeats_bursts_and_floods() -> None:
    now = [0.0]
    rules = NoticeFilter(repeat_window=300, min_interval=10, per_minute=3, clock=lambda: now[0])
    notices = board()
    first = notices.post("battery_low", {"battery": 0.12})
    assert rules.admit(first) is None
    now[0] = 5
    assert "within 10 s" in (rules.admit(notices.post("battery_low", {"battery": 0.1})) or "")
    now[0] = 20
    assert rules.admit(notices.post("battery_low", {"battery": 0.12})) == "a repeat"
    now[0] = 40
    assert rules.admit(notices.post("battery_low", {"battery": 0.09})) is None
    assert rules.admit(notices.post("docked")) is None
    now[0] = 55
    flood = rules.admit(notices.post("battery_low", {"battery": 0.05}))
    assert flood == "over 3 notices a minute from turtlebot"
    assert rules.dropped == 3


async def _served(notices: NoticeBoard) -> Any:
    server = FastMCP("notices-test")
    add_notice_route(server, notices)
    return serve_http(server, TOKEN)


async def test_get_notices_long_polls_behind_the_token() -> None:
    notices = board()
    async with await _served(notices) as served, httpx.AsyncClient(timeout=10) as http:
        url = notices_url(served.url)
        assert (await http.get(url)).status_code == 401
        auth = {"Authorization": f"Bearer {TOKEN}"}
        assert (await http.get(url, params={"wait": 99}, headers=auth)).status_code == 422
        waiting = asyncio.create_task(http.get(url, params={"after": 0, "wait": 5}, headers=auth))
        await asyncio.sleep(0.3)
        assert not waiting.done()
        notices.post("docked", message="turtlebot is back on its dock")
        batch = NoticeBatch.model_validate_json((await asyncio.wait_for(waiting, 3)).content)
    assert [(n.name, n.message) for n in batch.notices] == [("docked", "turtlebot is back on its dock")]
    assert (batch.board, batch.next) == (notices.board, 1)


async def test_the_watcher_enqueues_each_notice_once() -> None:
    notices = board()
    queued: list[DeviceNoticeEvent] = []
    two = asyncio.Event()

    async def enqueue(event: DeviceNoticeEvent) -> None:
        queued.append(event)
        if len(queued) >= 2:
            two.set()

    async with await _served(notices) as served:
        endpoint = DeviceEndpoint(
            "turtlebot", "ros", "exclusive", False, "TurtleBot", "prompt", served.url, TOKEN, "healthy"
        )
        watcher = NoticeWatcher(lambda: {"turtlebot": endpoint}, enqueue, wait=2)
        running = asyncio.create_task(watcher.run())
        try:
            notices.post("battery_low", {"battery": 0.12}, message="turtlebot: battery at 12 %")
            notices.post("battery_low", {"battery": 0.12}, message="turtlebot: battery at 12 %")
            notices.post("docked")
            await asyncio.wait_for(two.wait(), 5)
            await asyncio.sleep(0.3)  # time for a wrongly admitted third one to arrive
        finally:
            running.cancel()
            await asyncio.gather(running, return_exceptions=True)
    assert [(e.payload.name, e.payload.importance, e.source) for e in queued] == [
        ("battery_low", "notify", "turtlebot"),
        ("docked", "info", "turtlebot"),
    ]
    assert queued[0].payload.data == {"battery": 0.12}
    assert queued[0].idempotency_key == f"notice:turtlebot:{notices.board}:1"
    assert watcher.filter.dropped == 1


def test_notice_event_keys_are_stable_per_board_and_seq() -> None:
    notice = board().post("docked")
    assert notice_event(notice, "abc").idempotency_key == notice_event(notice, "abc").idempotency_key
    assert notice_event(notice, "abc").idempotency_key != notice_event(notice, "abd").idempotency_key


async def test_stopping_the_server_ends_a_pending_long_poll() -> None:
    notices = board()
    async with httpx.AsyncClient(timeout=10) as http:
        served_cm = await _served(notices)
        served = await served_cm.__aenter__()
        auth = {"Authorization": f"Bearer {TOKEN}"}
        waiting = asyncio.create_task(http.get(notices_url(served.url), params={"wait": 30}, headers=auth))
        await asyncio.sleep(0.3)
        loop = asyncio.get_running_loop()
        began = loop.time()
        await served_cm.__aexit__(None, None, None)
        assert loop.time() - began < 1.5  # not uvicorn's graceful-shutdown timeout
        answer = await asyncio.wait_for(waiting, 3)
    assert answer.status_code == 200
    assert NoticeBatch.model_validate_json(answer.content).notices == []
