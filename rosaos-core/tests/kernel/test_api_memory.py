"""GET /places and GET /sightings: what the floor map draws, behind the token, newest sighting first."""

from __future__ import annotations

import json
import time

import httpx
from kernel_support import AUTH, TestRuntime

from rosaos.memory.store import Place
from rosaos.receipts import Receipt


def detection(at: float, x: float, y: float) -> Receipt:
    """A turtlebot's ``detect_people`` call that found one person at (x, y) in its odometry frame."""
    person = {"x": x, "y": y, "frame": "odom", "anchor": "odom:turtlebot:1"}
    result = {"people": [person], "image": "turtlebot-1.jpg"}
    return Receipt(
        device="turtlebot", tool="detect_people", ok=True, result=json.dumps(result), started=at, duration=0.1
    )


async def test_places_and_sightings_are_listed_with_their_frame_and_the_kernels_clock(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    assert runtime.memory is not None and runtime.sightings is not None
    kitchen = Place(
        name="the kitchen",
        device="turtlebot",
        frame="odom",
        anchor="odom:turtlebot:1",
        x=2.0,
        y=1.0,
        saved_at=time.time(),
    )
    runtime.memory.save_place(kitchen)
    runtime.sightings.record_receipts(
        [detection(time.time() - 600, 9.0, 9.0), detection(time.time() - 60, 2.2, 1.1)]
    )

    places = (await client.get("/places", headers=AUTH)).json()["places"]
    assert [(p["name"], p["device"], p["x"], p["y"]) for p in places] == [
        ("the kitchen", "turtlebot", 2.0, 1.0)
    ]
    listed = (await client.get("/sightings", headers=AUTH)).json()
    newest, older = listed["sightings"]
    assert (newest["device"], newest["place"], newest["x"], newest["y"]) == (
        "turtlebot",
        "the kitchen",
        2.2,
        1.1,
    )
    assert older["place"] is None  # 7 m from the kitchen: near no named place
    assert 55 < listed["now"] - newest["at"] < 120
    assert listed["keep_days"] == 7.0
    assert len((await client.get("/sightings", params={"limit": 1}, headers=AUTH)).json()["sightings"]) == 1


async def test_memory_routes_need_the_token(client: httpx.AsyncClient) -> None:
    assert (await client.get("/places")).status_code == 401
    assert (await client.get("/sightings")).status_code == 401
    assert (await client.get("/sightings", params={"limit": 0}, headers=AUTH)).status_code == 422
