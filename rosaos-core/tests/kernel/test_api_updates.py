"""GET /updates: server-sent events over a real socket (resumable), or JSON pages for polling."""

from __future__ import annotations

import asyncio
import json
from collections.abc import AsyncIterator
from typing import Any

import httpx
import pytest

from rosaos.kernel.updates import UpdateStream

from .kernel_support import AUTH, eventually

SSE = {**AUTH, "Accept": "text/event-stream"}


async def sse_events(response: httpx.Response) -> AsyncIterator[dict[str, Any]]:
    """Parse a text/event-stream body into ``{"id": ..., "data": ...}`` dicts (comments skipped)."""
    fields: dict[str, Any] = {}
    async for line in response.aiter_lines():
        if not line:
            if "data" in fields:
                yield {"id": fields.get("id"), "data": json.loads(fields["data"])}
            fields = {}
        elif not line.startswith(":"):
            name, _, value = line.partition(":")
            fields[name] = value.removeprefix(" ")


async def read(events: AsyncIterator[dict[str, Any]], count: int) -> list[dict[str, Any]]:
    async with asyncio.timeout(10):
        return [await anext(events) for _ in range(count)]


async def test_sse_sends_the_backlog_then_live_updates_in_order(served: str, updates: UpdateStream) -> None:
    await updates.publish("notice", "one")
    await updates.publish("notice", "two")
    async with (
        httpx.AsyncClient(base_url=served) as http,
        http.stream("GET", "/updates", headers=SSE) as response,
    ):
        assert response.status_code == 200
        assert response.headers["content-type"].startswith("text/event-stream")
        events = sse_events(response)
        backlog = await read(events, 2)
        await eventually(lambda: updates.follower_count == 1, message="the stream following")
        await updates.publish("kernel_reply", "three")
        live = await read(events, 1)
    received = backlog + live
    assert [event["data"]["text"] for event in received] == ["one", "two", "three"]
    assert [event["id"] for event in received] == [str(event["data"]["id"]) for event in received]
    assert live[0]["data"]["kind"] == "kernel_reply"


async def test_sse_resumes_after_last_event_id(served: str, updates: UpdateStream) -> None:
    ids = [await updates.publish("notice", f"n{n}") for n in range(4)]
    headers = {**SSE, "Last-Event-ID": str(ids[1])}
    async with (
        httpx.AsyncClient(base_url=served) as http,
        http.stream("GET", "/updates", headers=headers) as response,
    ):
        received = await read(sse_events(response), 2)
    assert [event["data"]["text"] for event in received] == ["n2", "n3"]


async def test_sse_starts_after_the_after_parameter(served: str, updates: UpdateStream) -> None:
    ids = [await updates.publish("notice", f"n{n}") for n in range(3)]
    async with (
        httpx.AsyncClient(base_url=served) as http,
        http.stream("GET", "/updates", params={"after": ids[1]}, headers=SSE) as response,
    ):
        received = await read(sse_events(response), 1)
    assert received[0]["data"]["text"] == "n2"


async def test_a_disconnected_sse_client_stops_following(served: str, updates: UpdateStream) -> None:
    async with (
        httpx.AsyncClient(base_url=served) as http,
        http.stream("GET", "/updates", headers=SSE) as response,
    ):
        assert response.status_code == 200
        await eventually(lambda: updates.follower_count == 1, message="the stream following")
    await eventually(lambda: updates.follower_count == 0, message="the follower leaving after the disconnect")


async def test_a_bad_last_event_id_is_refused(client: httpx.AsyncClient) -> None:
    response = await client.get("/updates", headers={**SSE, "Last-Event-ID": "yesterday"})
    assert response.status_code == 422
    assert "Last-Event-ID" in response.json()["detail"]


@pytest.mark.parametrize("none", ["null", ""])
async def test_a_null_or_empty_last_event_id_means_none_seen(client: httpx.AsyncClient, none: str) -> None:
    response = await client.get("/updates", headers={"Last-Event-ID": none, **AUTH})
    assert response.status_code == 200


async def test_polling_pages_through_updates_after_an_id(
    client: httpx.AsyncClient, updates: UpdateStream
) -> None:
    ids = [await updates.publish("notice", f"n{n}") for n in range(5)]
    first = (await client.get("/updates", params={"after": 0, "limit": 3}, headers=AUTH)).json()
    second = (
        await client.get("/updates", params={"after": first["last_id"], "limit": 3}, headers=AUTH)
    ).json()
    third = (await client.get("/updates", params={"after": second["last_id"]}, headers=AUTH)).json()
    assert [u["text"] for u in first["updates"]] == ["n0", "n1", "n2"]
    assert [u["text"] for u in second["updates"]] == ["n3", "n4"]
    assert third == {"updates": [], "last_id": ids[-1]}


async def test_polling_without_after_returns_the_most_recent_updates(
    client: httpx.AsyncClient, updates: UpdateStream
) -> None:
    for n in range(5):
        await updates.publish("notice", f"n{n}")
    page = (await client.get("/updates", params={"limit": 2}, headers=AUTH)).json()
    assert [u["text"] for u in page["updates"]] == ["n3", "n4"]


async def test_polling_limits_are_validated(client: httpx.AsyncClient) -> None:
    response = await client.get("/updates", params={"limit": 0}, headers=AUTH)
    assert response.status_code == 422
    assert "query.limit" in response.json()["detail"]


async def test_a_cursor_from_a_reset_store_starts_afresh(
    client: httpx.AsyncClient, updates: UpdateStream
) -> None:
    await updates.publish("notice", "first in the new store")
    page = (await client.get("/updates", params={"after": 500}, headers=AUTH)).json()
    assert [u["text"] for u in page["updates"]] == ["first in the new store"]
