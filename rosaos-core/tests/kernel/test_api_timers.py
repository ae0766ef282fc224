"""GET /timers and DELETE /timers/{id}: typed answers, behind the token, clear errors."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import httpx

from .kernel_support import AUTH, TestRuntime


async def test_timers_are_listed_soonest_first_and_cancelled_by_id(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    assert runtime.timers is not None
    later = await runtime.timers.set("stop the music", datetime.now(UTC) + timedelta(hours=2))
    sooner = await runtime.timers.set("turn off the kitchen light", datetime.now(UTC) + timedelta(minutes=10))
    listed = (await client.get("/timers", headers=AUTH)).json()
    assert [timer["id"] for timer in listed["timers"]] == [sooner.id, later.id]
    assert listed["timers"][0]["state"] == "pending" and listed["now"]

    cancelled = await client.delete(f"/timers/{sooner.id}", headers=AUTH)
    assert cancelled.status_code == 200 and cancelled.json()["state"] == "cancelled"
    again = await client.delete(f"/timers/{sooner.id}", headers=AUTH)
    assert again.status_code == 409 and "already cancelled" in again.json()["detail"]
    [notice] = [u for u in await runtime.updates.after(0) if u.kind == "notice"]
    assert notice.text == f"timer {sooner.id} cancelled: turn off the kitchen light"
    assert notice.data["timer"]["state"] == "cancelled"
    assert [t["id"] for t in (await client.get("/timers", headers=AUTH)).json()["timers"]] == [later.id]
    everything = (await client.get("/timers", params={"all": "true"}, headers=AUTH)).json()["timers"]
    assert [(t["id"], t["state"]) for t in everything] == [(later.id, "pending"), (sooner.id, "cancelled")]


async def test_an_unknown_timer_is_404_and_the_token_is_required(client: httpx.AsyncClient) -> None:
    missing = await client.delete("/timers/7", headers=AUTH)
    assert missing.status_code == 404 and "GET /timers" in missing.json()["detail"]
    assert (await client.get("/timers")).status_code == 401
    assert (await client.delete("/timers/0", headers=AUTH)).status_code == 422


async def test_the_openapi_document_types_the_timer_answers(client: httpx.AsyncClient) -> None:
    schema = (await client.get("/openapi.json")).json()
    listed = schema["paths"]["/timers"]["get"]["responses"]["200"]["content"]["application/json"]["schema"]
    assert listed == {"$ref": "#/components/schemas/TimerList"}
    assert set(schema["components"]["schemas"]["Timer"]["properties"]) >= {"id", "action", "due", "state"}
    assert "409" in schema["paths"]["/timers/{timer_id}"]["delete"]["responses"]
