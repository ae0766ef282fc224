"""Who may connect to a rosbridge simulator: a client with its token, and no web page.

The simulators listen on loopback, where any local process, or a browser page that finds the
port, could publish ``/cmd_vel`` past the leases, the latch and the allow-lists. The ``sim``
backend therefore always gives its simulator a fresh token (and uses it itself), and every
simulator refuses a WebSocket handshake that carries a browser ``Origin`` it was not told to allow.
"""

from __future__ import annotations

import json
from typing import Any

from websockets.asyncio.client import connect
from websockets.exceptions import InvalidStatus

PUBLISH = json.dumps(
    {"op": "publish", "topic": "/cmd_vel", "msg": {"linear": {"x": 0.2}, "angular": {"z": 0.0}}}
)


async def status_of(url: str, **options: Any) -> int:
    """The HTTP status the handshake got: 101 when the WebSocket opened (and a publish was sent)."""
    try:
        async with connect(url, open_timeout=5, **options) as socket:
            await socket.send(PUBLISH)
    except InvalidStatus as refused:
        return refused.response.status_code
    return 101


async def test_the_sim_backend_token_keeps_other_local_clients_out(open_robot: Any) -> None:
    async with open_robot() as robot:
        url = robot.backend.simulator.simulator.url
        state = await robot.call("get_state")  # the backend itself connects, with the token
        anonymous = await status_of(url)
        linear = robot.world.linear
    assert "x" in state
    assert anonymous == 401
    assert linear == 0.0, "a client without the token moved the robot"


async def test_a_web_page_origin_is_refused_even_with_the_token(simulator: Any) -> None:
    sim = simulator("turtlebot4", token="s3cret")
    url = sim.simulator.url
    bearer = {"Authorization": "Bearer s3cret"}
    from_page = await status_of(url, additional_headers=bearer, origin="http://evil.example")
    from_program = await status_of(url, additional_headers=bearer)
    assert from_page == 403
    assert from_program == 101


async def test_an_allowed_origin_may_connect(simulator: Any) -> None:
    sim = simulator("turtlebot4", token="s3cret")
    sim.simulator.server.origins = frozenset({"http://localhost:8080"})
    bearer = {"Authorization": "Bearer s3cret"}
    assert (
        await status_of(sim.simulator.url, additional_headers=bearer, origin="http://localhost:8080") == 101
    )
