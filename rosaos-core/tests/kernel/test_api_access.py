"""Who gets in: the bearer token, the same-origin rule, the open routes, and login codes."""

from __future__ import annotations

import httpx
import pytest

from .kernel_support import AUTH, ORIGIN, TOKEN, TestRuntime

PROTECTED = [
    ("GET", "/processes"),
    ("POST", "/processes/1/terminate"),
    ("GET", "/devices"),
    ("GET", "/updates"),
    ("GET", "/events/1"),
    ("POST", "/chat"),
    ("POST", "/stt"),
    ("POST", "/event"),
    ("POST", "/login-codes"),
]


@pytest.mark.parametrize(("method", "path"), PROTECTED)
async def test_protected_routes_need_the_token(client: httpx.AsyncClient, method: str, path: str) -> None:
    response = await client.request(method, path, json={"text": "hi"})
    assert response.status_code == 401
    assert response.json()["detail"].startswith("missing bearer token")


async def test_a_wrong_token_is_refused(client: httpx.AsyncClient) -> None:
    response = await client.get("/processes", headers={"Authorization": "Bearer not-the-token"})
    assert response.status_code == 401
    assert response.json()["detail"].startswith("wrong bearer token")


async def test_the_token_is_not_accepted_in_the_query_string(client: httpx.AsyncClient) -> None:
    # It would end up in access logs; the page streams with fetch and the header instead.
    response = await client.get("/updates", params={"token": TOKEN})
    assert response.status_code == 401


@pytest.mark.parametrize("origin", ["http://evil.example", "http://127.0.0.1:9999", "null"])
async def test_browser_requests_from_foreign_origins_are_refused(
    client: httpx.AsyncClient, origin: str
) -> None:
    for method, path in [("GET", "/processes"), ("POST", "/login"), ("GET", "/health")]:
        response = await client.request(method, path, headers={**AUTH, "Origin": origin}, json={"code": "x"})
        assert response.status_code == 403
        assert origin in response.json()["detail"]


async def test_requests_from_the_page_s_own_origin_pass(client: httpx.AsyncClient) -> None:
    response = await client.get("/processes", headers={**AUTH, "Origin": ORIGIN})
    assert response.status_code == 200


async def test_health_is_open_and_tells_nothing_secret(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    await client.post("/chat", json={"text": "hello"}, headers=AUTH)
    response = await client.get("/health")
    assert response.status_code == 200
    health = response.json()
    assert set(health) == {"status", "version", "model", "model_notice", "uptime_seconds", "pending_events"}
    assert health["status"] == "ok"
    assert health["model"] == "offline default"
    assert health["model_notice"] == runtime.model_notice
    assert health["pending_events"] == 1
    assert TOKEN not in response.text


async def test_the_api_description_is_published(client: httpx.AsyncClient) -> None:
    schema = (await client.get("/openapi.json")).json()
    assert {"/chat", "/stt", "/event", "/updates", "/processes", "/devices", "/health"} <= set(
        schema["paths"]
    )
    assert schema["components"]["securitySchemes"]["HTTPBearer"]["scheme"] == "bearer"
    assert (await client.get("/docs")).status_code == 200


async def test_a_login_code_buys_the_token_once(client: httpx.AsyncClient, runtime: TestRuntime) -> None:
    code = runtime.login_codes.mint()
    first = await client.post("/login", json={"code": code})
    assert first.status_code == 200
    assert first.json() == {"token": TOKEN, "token_type": "bearer"}
    assert first.headers["cache-control"] == "no-store"
    again = await client.post("/login", json={"code": code})
    assert again.status_code == 401
    assert "already used" in again.json()["detail"]


async def test_a_wrong_login_code_is_refused(client: httpx.AsyncClient) -> None:
    response = await client.post("/login", json={"code": "guess"})
    assert response.status_code == 401
    assert TOKEN not in response.text


async def test_login_codes_are_minted_with_the_token_as_links(client: httpx.AsyncClient) -> None:
    response = await client.post("/login-codes", headers=AUTH)
    assert response.status_code == 201
    link = response.json()
    assert link["url"] == f"{ORIGIN}/#login={link['code']}"
    assert link["expires_in"] == 600
    assert (await client.post("/login", json={"code": link["code"]})).status_code == 200


async def test_a_rebound_host_name_is_refused_even_with_its_own_origin(client: httpx.AsyncClient) -> None:
    # DNS rebinding: evil.example resolves to 127.0.0.1, so the page is "same origin" with itself.
    rebound = {**AUTH, "Host": "evil.example:8765", "Origin": "http://evil.example:8765"}
    response = await client.post("/chat", headers=rebound, json={"text": "turn on the kitchen light"})
    assert response.status_code == 421
    assert "host 'evil.example:8765' is not served here" in response.json()["detail"]


@pytest.mark.parametrize("host", ["localhost:8765", "[::1]:8765", "127.0.0.2:8765", "127.0.0.1"])
async def test_loopback_host_names_pass(client: httpx.AsyncClient, host: str) -> None:
    response = await client.get("/processes", headers={**AUTH, "Host": host})
    assert response.status_code == 200


async def test_a_host_allowed_in_config_passes(runtime: TestRuntime) -> None:
    from rosaos.kernel.api.app import create_app

    app = create_app(runtime, allowed_hosts=["desk.local"])
    async with httpx.AsyncClient(
        transport=httpx.ASGITransport(app=app), base_url="http://desk.local:8765"
    ) as http:
        allowed = await http.get("/processes", headers={**AUTH, "Origin": "http://desk.local:8765"})
        other = await http.get("/processes", headers={**AUTH, "Host": "lab.local:8765"})
    assert allowed.status_code == 200
    assert other.status_code == 421
