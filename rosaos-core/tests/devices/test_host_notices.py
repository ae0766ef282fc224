"""``POST /host/notices``: every board a host process serves, read with one long poll (issue 27).

Real device servers on loopback (several in this process, as in the shared host) and the kernel's
real :class:`NoticeWatcher`.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import AsyncIterator
from typing import Any

import httpx
from fastmcp import FastMCP

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.devices.host_notices import HOST_BOARDS, HostNoticeAnswer
from rosaos.devices.serve import ServedDevice, add_notice_route, serve_http
from rosaos.events.types import DeviceNoticeEvent
from rosaos.notices.notice_board import NoticeBoard
from rosaos.notices.notice_watcher import NoticeWatcher, host_groups, host_notices_url

TOKEN = "host-notice-token-0123456789"
OTHER = "another-token-9876543210"


@contextlib.asynccontextmanager
async def served(*boards: tuple[NoticeBoard, str]) -> AsyncIterator[list[ServedDevice]]:
    async with contextlib.AsyncExitStack() as stack:
        devices = []
        for board, token in boards:
            server = FastMCP(f"{board.instance}-test")
            add_notice_route(server, board)
            devices.append(await stack.enter_async_context(serve_http(server, token)))
        yield devices


def endpoint(name: str, device: ServedDevice, host: str, token: str = TOKEN) -> DeviceEndpoint:
    return DeviceEndpoint(
        name, "tapo", "shared", False, name, "prompt", device.url, token, "healthy", host=host
    )


async def test_one_request_reads_every_board_the_process_serves_with_that_token() -> None:
    a, b, c = NoticeBoard("lamp_a"), NoticeBoard("lamp_b"), NoticeBoard("lamp_c")
    async with (
        served((a, TOKEN), (b, TOKEN), (c, OTHER)) as (first, _, _),
        httpx.AsyncClient(timeout=10) as http,
    ):
        url, auth = host_notices_url(first.url), {"Authorization": f"Bearer {TOKEN}"}
        everything: dict[str, Any] = {
            "boards": {name: {} for name in ("lamp_a", "lamp_b", "lamp_c", "ghost")}
        }
        assert (await http.post(url, json=everything)).status_code == 401
        assert (await http.post(url, json={"boards": {}, "wait": 99}, headers=auth)).status_code == 422
        # First read: a new board life for each known board, answered at once.
        first_read = HostNoticeAnswer.model_validate_json(
            (await http.post(url, json=everything, headers=auth)).content
        )
        assert sorted(first_read.batches) == ["lamp_a", "lamp_b"]
        assert sorted(first_read.unknown) == ["ghost", "lamp_c"]  # lamp_c is served with another token
        cursors = {
            name: {"after": batch.next, "board": batch.board} for name, batch in first_read.batches.items()
        }
        waiting = asyncio.create_task(http.post(url, json={"boards": cursors, "wait": 5}, headers=auth))
        await asyncio.sleep(0.3)
        assert not waiting.done()  # nothing new: it waits
        b.post("flickering", message="lamp_b flickers")
        answer = HostNoticeAnswer.model_validate_json((await asyncio.wait_for(waiting, 3)).content)
    assert list(answer.batches) == ["lamp_b"]  # only the board with something new
    assert [notice.message for notice in answer.batches["lamp_b"].notices] == ["lamp_b flickers"]
    assert "lamp_a" not in HOST_BOARDS  # a board leaves the host's list when its server stops


def test_devices_are_grouped_by_host_and_token() -> None:
    device = ServedDevice("http://127.0.0.1:1/mcp", None, None)  # type: ignore[arg-type]
    endpoints = {
        "lamp_1": endpoint("lamp_1", device, "shared"),
        "lamp_0": endpoint("lamp_0", device, "shared"),
        "remote": endpoint("remote", device, "shared", OTHER),
        "robot": endpoint("robot", device, ""),
    }
    assert host_groups(endpoints) == [("lamp_0", "lamp_1"), ("remote",), ("robot",)]


async def test_the_watcher_holds_one_poll_for_a_host_and_delivers_each_notice_once() -> None:
    boards = [NoticeBoard(f"lamp_{k}") for k in range(5)]
    queued: list[DeviceNoticeEvent] = []
    three = asyncio.Event()

    async def enqueue(event: DeviceNoticeEvent) -> None:
        queued.append(event)
        if len(queued) >= 3:
            three.set()

    async with served(*[(board, TOKEN) for board in boards]) as devices:
        endpoints = {f"lamp_{k}": endpoint(f"lamp_{k}", device, "shared") for k, device in enumerate(devices)}
        watcher = NoticeWatcher(lambda: endpoints, enqueue, wait=2)
        running = asyncio.create_task(watcher.run())
        try:
            await asyncio.sleep(0.5)
            assert watcher.pollers() == [tuple(sorted(endpoints))]  # one long poll, not five
            boards[4].post("flickering", message="lamp 4 flickers")
            boards[1].post("flickering", message="lamp 1 flickers")
            await asyncio.sleep(0.5)
            boards[4].post("overheating", message="lamp 4 is hot")
            await asyncio.wait_for(three.wait(), 5)
            await asyncio.sleep(2.5)  # a full poll later: nothing is delivered twice
        finally:
            running.cancel()
            await asyncio.gather(running, return_exceptions=True)
    assert sorted(event.payload.message for event in queued) == [
        "lamp 1 flickers",
        "lamp 4 flickers",
        "lamp 4 is hot",
    ]


async def test_a_member_the_host_does_not_know_is_polled_on_its_own() -> None:
    known, stray = NoticeBoard("lamp_a"), NoticeBoard("lamp_x")
    queued: list[DeviceNoticeEvent] = []
    delivered = asyncio.Event()

    async def enqueue(event: DeviceNoticeEvent) -> None:
        queued.append(event)
        delivered.set()

    async with served((known, TOKEN), (stray, TOKEN)) as devices:
        HOST_BOARDS.remove(stray)  # as if lamp_x were served by another process than lamp_a
        endpoints = {
            "lamp_a": endpoint("lamp_a", devices[0], "shared"),
            "lamp_x": endpoint("lamp_x", devices[1], "shared"),
        }
        watcher = NoticeWatcher(lambda: endpoints, enqueue, wait=2)
        running = asyncio.create_task(watcher.run())
        try:
            await asyncio.sleep(0.5)
            stray.post("flickering", message="lamp x flickers")
            await asyncio.wait_for(delivered.wait(), 5)
        finally:
            running.cancel()
            await asyncio.gather(running, return_exceptions=True)
    assert [event.payload.message for event in queued] == ["lamp x flickers"]
