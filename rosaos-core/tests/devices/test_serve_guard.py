"""Device MCP servers answer only to loopback and allowed Host names, and to no foreign page."""

from __future__ import annotations

import httpx
from fastmcp import FastMCP

from rosaos.devices.serve import serve_http

TOKEN = "device-token"


def _server() -> FastMCP:
    server = FastMCP("guarded")

    @server.tool(annotations={"readOnlyHint": True})
    def get_state() -> dict[str, bool]:
        """The state."""
        return {"on": True}

    return server


async def _post(url: str, **headers: str) -> httpx.Response:
    async with httpx.AsyncClient(timeout=10) as http:
        return await http.post(url, headers={"Authorization": f"Bearer {TOKEN}", **headers}, json={})


async def test_a_foreign_host_name_is_refused_with_the_fix() -> None:
    async with serve_http(_server(), TOKEN) as served:
        response = await _post(served.url, Host="evil.example")
    assert response.status_code == 421
    assert "--allow-host" in response.json()["detail"]


async def test_a_foreign_origin_is_refused_on_loopback() -> None:
    async with serve_http(_server(), TOKEN) as served:
        response = await _post(served.url, Origin="http://evil.example")
    assert response.status_code == 403


async def test_an_allowed_host_reaches_the_token_check() -> None:
    async with serve_http(_server(), "another-token", allowed_hosts=["robot-host"]) as served:
        allowed = await _post(served.url, Host="robot-host:9100")
        refused = await _post(served.url, Host="lab-host:9100")
    assert allowed.status_code == 401  # past the host check: only the token is wrong
    assert refused.status_code == 421
