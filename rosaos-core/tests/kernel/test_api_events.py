"""POST /chat, /stt and /event: validated, committed, then answered 202 with the event id."""

from __future__ import annotations

from typing import Any

import httpx
import pytest

from rosaos.events.types import UserText
from rosaos.kernel.event_store import EventStore
from rosaos.kernel.intake import Queued

from .kernel_support import AUTH, TestRuntime


async def test_chat_commits_a_user_typed_event_and_answers_202(
    client: httpx.AsyncClient, store: EventStore
) -> None:
    response = await client.post("/chat", json={"text": "  turn on the kitchen light "}, headers=AUTH)
    assert response.status_code == 202
    body = response.json()
    assert body == {"id": body["id"], "duplicate": False}
    event = await store.get(body["id"])
    assert event is not None
    assert (event.kind, event.source, event.payload) == (
        "user_typed",
        "chat",
        UserText(text="turn on the kitchen light"),
    )


async def test_stt_commits_a_user_said_event(client: httpx.AsyncClient, store: EventStore) -> None:
    response = await client.post("/stt", json={"text": "hello", "source": "reachy"}, headers=AUTH)
    assert response.status_code == 202
    event = await store.get(response.json()["id"])
    assert event is not None
    assert (event.kind, event.source) == ("user_said", "reachy")


async def test_a_repeated_idempotency_key_answers_the_first_id_and_enqueues_nothing(
    client: httpx.AsyncClient, store: EventStore
) -> None:
    body = {"text": "hello", "idempotency_key": "web-1"}
    first = await client.post("/chat", json=body, headers=AUTH)
    second = await client.post("/chat", json=body, headers=AUTH)
    assert second.status_code == 202
    assert second.json() == {"id": first.json()["id"], "duplicate": True}
    assert await store.pending_count() == 1


async def test_a_key_reused_with_a_different_body_is_a_conflict(
    client: httpx.AsyncClient, store: EventStore
) -> None:
    first = await client.post(
        "/chat", json={"text": "turn on the light", "idempotency_key": "web-2"}, headers=AUTH
    )
    reused = await client.post(
        "/chat", json={"text": "turn off the light", "idempotency_key": "web-2"}, headers=AUTH
    )
    assert reused.status_code == 409
    assert f"already used for event {first.json()['id']} with a different body" in reused.json()["detail"]
    assert await store.pending_count() == 1


async def test_the_idempotency_key_header_works_like_the_body_field(
    client: httpx.AsyncClient, store: EventStore
) -> None:
    headers = {**AUTH, "Idempotency-Key": "voice-7"}
    first = await client.post("/stt", json={"text": "hello"}, headers=headers)
    second = await client.post("/stt", json={"text": "hello", "idempotency_key": "voice-7"}, headers=AUTH)
    assert second.json() == {"id": first.json()["id"], "duplicate": True}


async def test_a_header_and_body_key_that_differ_are_refused(client: httpx.AsyncClient) -> None:
    response = await client.post(
        "/chat", json={"text": "hi", "idempotency_key": "a"}, headers={**AUTH, "Idempotency-Key": "b"}
    )
    assert response.status_code == 409
    assert "differ" in response.json()["detail"]


async def test_event_accepts_each_kind(client: httpx.AsyncClient, store: EventStore) -> None:
    bodies: list[dict[str, Any]] = [
        {"kind": "user_said", "payload": {"text": "hi"}},
        {"kind": "user_typed", "payload": {"text": "hi"}},
        {"kind": "device_notice", "source": "vacuum", "payload": {"device": "vacuum", "message": "stuck"}},
        {"kind": "error", "source": "kernel", "payload": {"message": "boom", "source_event": 1}},
    ]
    kinds = []
    for body in bodies:
        response = await client.post("/event", json=body, headers=AUTH)
        assert response.status_code == 202, response.text
        event = await store.get(response.json()["id"])
        assert event is not None
        kinds.append(event.kind)
    assert kinds == [body["kind"] for body in bodies]


@pytest.mark.parametrize(
    ("body", "reason"),
    [
        ({"kind": "worker_callback", "payload": {"process_id": 7, "status": "ok"}}, "the pool's pipe"),
        (
            {"kind": "timer_fired", "payload": {"timer_id": 1, "action": "x", "due": "2026-01-01T00:00:00Z"}},
            "the kernel's own table",
        ),
    ],
)
async def test_events_only_the_kernel_queues_are_refused_from_outside(
    client: httpx.AsyncClient, store: EventStore, body: dict[str, Any], reason: str
) -> None:
    """A process's end has one route (the worker's pipe): a posted one would race it."""
    response = await client.post("/event", json=body, headers=AUTH)
    assert response.status_code == 422
    assert reason in response.json()["detail"]
    assert await store.pending_count() == 0


async def test_an_accepted_event_is_announced_on_the_updates_stream(client: httpx.AsyncClient) -> None:
    accepted = (
        await client.post("/chat", json={"text": "hello", "idempotency_key": "k"}, headers=AUTH)
    ).json()
    await client.post("/chat", json={"text": "hello", "idempotency_key": "k"}, headers=AUTH)
    page = (await client.get("/updates", params={"after": 0}, headers=AUTH)).json()
    assert [(u["kind"], u["text"], u["event_id"]) for u in page["updates"]] == [
        ("event", "[User typed] hello", accepted["id"])
    ]


@pytest.mark.parametrize(
    ("path", "body", "reason"),
    [
        ("/chat", {"text": "   "}, "body.text: String should have at least 1 character"),
        ("/chat", {"text": "x" * 4001}, "body.text: String should have at most 4000 characters"),
        ("/chat", {}, "body.text: Field required"),
        ("/chat", {"text": "hi", "colour": "red"}, "body.colour: Extra inputs are not permitted"),
        ("/event", {"kind": "telepathy", "payload": {}}, "does not match any of the expected tags"),
        ("/event", {"payload": {"text": "hi"}}, "Unable to extract tag using discriminator 'kind'"),
        ("/event", {"kind": "user_typed", "payload": {"text": ""}}, "body.user_typed.payload.text"),
        ("/event", {"kind": "device_notice", "payload": {"device": "dog", "message": ""}}, "payload.message"),
        (
            "/event",
            {"kind": "device_notice", "payload": {"device": "dog", "message": "hi", "importance": "loud"}},
            "payload.importance",
        ),
        ("/event", {"kind": "device_notice", "payload": {"message": "hi"}}, "device: Field required"),
    ],
)
async def test_malformed_bodies_are_refused_with_the_reason(
    client: httpx.AsyncClient, store: EventStore, path: str, body: dict[str, Any], reason: str
) -> None:
    response = await client.post(path, json=body, headers=AUTH)
    assert response.status_code == 422
    assert reason in response.json()["detail"]
    assert response.json()["errors"]
    assert await store.pending_count() == 0


async def test_a_body_that_is_not_json_is_refused_with_the_reason(client: httpx.AsyncClient) -> None:
    response = await client.post(
        "/chat", content=b"{text: hi", headers={**AUTH, "Content-Type": "application/json"}
    )
    assert response.status_code == 422
    assert response.json()["detail"].startswith("invalid request: body: not valid JSON")


async def test_an_oversized_body_is_refused(client: httpx.AsyncClient) -> None:
    response = await client.post("/chat", json={"text": "x" * 2_000_000}, headers=AUTH)
    assert response.status_code == 413


async def test_get_event_shows_whether_it_was_handled(client: httpx.AsyncClient, store: EventStore) -> None:
    event_id = (await client.post("/chat", json={"text": "hello"}, headers=AUTH)).json()["id"]
    before = (await client.get(f"/events/{event_id}", headers=AUTH)).json()
    await store.mark_handled(event_id)
    after = (await client.get(f"/events/{event_id}", headers=AUTH)).json()
    assert before["handled"] is False
    assert after["handled"] is True
    assert after["payload"] == {"text": "hello"}


async def test_an_unknown_event_is_404_with_a_message(client: httpx.AsyncClient) -> None:
    response = await client.get("/events/999", headers=AUTH)
    assert response.status_code == 404
    assert response.json()["detail"].startswith("no event 999")


async def test_a_failing_side_effect_still_answers_202_and_reports_the_error(
    client: httpx.AsyncClient, runtime: TestRuntime, store: EventStore
) -> None:
    async def broken(queued: Queued) -> None:
        raise RuntimeError("lease table unavailable")

    runtime.intake.on("user_typed", broken)
    response = await client.post("/chat", json={"text": "hello"}, headers=AUTH)
    assert response.status_code == 202
    assert await store.get(response.json()["id"]) is not None
    page = (await client.get("/updates", params={"after": 0}, headers=AUTH)).json()
    assert page["updates"][-1]["kind"] == "error"
    assert "lease table unavailable" in page["updates"][-1]["text"]


async def test_an_event_id_beyond_sqlite_integers_is_invalid_not_a_server_error(
    client: httpx.AsyncClient,
) -> None:
    response = await client.get("/events/9223372036854775808", headers=AUTH)
    assert response.status_code == 422
    assert "event_id" in response.json()["detail"]


async def test_the_largest_published_id_is_exact_as_a_json_number(client: httpx.AsyncClient) -> None:
    schema = (await client.get("/openapi.json")).json()
    [parameter] = schema["paths"]["/events/{event_id}"]["get"]["parameters"]
    maximum = parameter["schema"]["maximum"]
    assert float(maximum) == maximum  # a double holds it: a client sending the maximum sends it exactly
    assert (await client.get(f"/events/{maximum}", headers=AUTH)).status_code == 404
    assert (await client.get(f"/events/{maximum + 1}", headers=AUTH)).status_code == 422


async def test_notice_data_nested_too_deep_is_refused_not_a_server_error(
    client: httpx.AsyncClient, store: EventStore
) -> None:
    data: dict[str, object] = {}
    for _ in range(300):
        data = {"x": data}
    body = {
        "kind": "device_notice",
        "source": "lamp",
        "payload": {"device": "lamp", "message": "hi", "data": data},
    }
    response = await client.post("/event", json=body, headers=AUTH)
    assert response.status_code == 422
    assert "nested more than 32 levels deep" in response.json()["detail"]
    assert await store.pending_count() == 0
