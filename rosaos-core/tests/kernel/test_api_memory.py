"""GET /places and GET /sightings: what the floor map draws, behind the token, newest sighting first."""

from __future__ import annotations

import json
import time
from pathlib import Path

import httpx

from rosaos.memory.store import Place
from rosaos.receipts import Receipt

from .kernel_support import AUTH, TestRuntime

JPEG = b"\xff\xd8\xff\xe0 a sighting's picture"


def detection(at: float, x: float, y: float) -> Receipt:
    """A turtlebot's ``detect_people`` call that found one person at (x, y) in its odometry frame."""
    person = {"x": x, "y": y, "frame": "odom", "anchor": "odom:turtlebot:1"}
    result = {"people": [person], "image": "turtlebot-1.jpg"}
    return Receipt(
        device="turtlebot", tool="detect_people", ok=True, result=json.dumps(result), started=at, duration=0.1
    )


def kitchen_at(x: float, y: float, name: str = "the kitchen") -> Place:
    return Place(
        name=name, device="turtlebot", frame="odom", anchor="odom:turtlebot:1", x=x, y=y, saved_at=time.time()
    )


async def test_a_place_is_renamed_and_keeps_its_pose_and_frame(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.memory.save_place(kitchen_at(2.0, 1.0))
    response = await client.patch("/places/Kitchen", json={"name": "the galley"}, headers=AUTH)
    assert response.status_code == 200, response.text
    assert (response.json()["name"], response.json()["x"], response.json()["anchor"]) == (
        "the galley",
        2.0,
        "odom:turtlebot:1",
    )
    assert [p.name for p in runtime.memory.places()] == ["the galley"]


async def test_a_place_is_deleted_and_the_answer_is_what_was_deleted(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.memory.save_place(kitchen_at(2.0, 1.0))
    response = await client.delete("/places/the%20kitchen", headers=AUTH)
    assert response.status_code == 200, response.text
    assert response.json()["name"] == "the kitchen"
    assert runtime.memory.places() == []


async def test_renaming_or_deleting_an_unknown_place_is_404_naming_the_known_ones(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.memory.save_place(kitchen_at(2.0, 1.0))
    renamed = await client.patch("/places/the attic", json={"name": "the loft"}, headers=AUTH)
    deleted = await client.delete("/places/the attic", headers=AUTH)
    for response in (renamed, deleted):
        assert response.status_code == 404
        assert "the attic" in response.json()["detail"] and "the kitchen" in response.json()["detail"]
    assert [p.name for p in runtime.memory.places()] == ["the kitchen"]


async def test_a_name_another_place_has_is_409_and_changes_nothing(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.memory.save_place(kitchen_at(2.0, 1.0))
    runtime.memory.save_place(kitchen_at(5.0, 5.0, "the hall"))
    response = await client.patch("/places/the hall", json={"name": "The Kitchen"}, headers=AUTH)
    assert response.status_code == 409
    assert "already a place called" in response.json()["detail"]
    assert {(p.name, p.x) for p in runtime.memory.places()} == {("the kitchen", 2.0), ("the hall", 5.0)}


async def test_an_empty_blank_or_too_long_name_is_422_and_changes_nothing(
    client: httpx.AsyncClient, runtime: TestRuntime
) -> None:
    runtime.memory.save_place(kitchen_at(2.0, 1.0))
    for bad in ({"name": ""}, {"name": "   "}, {"name": "x" * 81}, {}, {"name": "ok", "extra": 1}):
        response = await client.patch("/places/the kitchen", json=bad, headers=AUTH)
        assert response.status_code == 422, (bad, response.text)
        assert response.json()["detail"], bad
    assert [p.name for p in runtime.memory.places()] == ["the kitchen"]


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
    assert (await client.patch("/places/the kitchen", json={"name": "x"})).status_code == 401
    assert (await client.delete("/places/the kitchen")).status_code == 401
    assert (await client.get("/sightings", params={"limit": 0}, headers=AUTH)).status_code == 422


def save_picture(path: Path) -> None:
    path.parent.mkdir(exist_ok=True)
    path.write_bytes(JPEG)


async def test_a_sightings_picture_is_served_behind_the_token_and_the_host_check(
    client: httpx.AsyncClient, runtime: TestRuntime, images_dir: Path
) -> None:
    save_picture(images_dir / "turtlebot-1.jpg")
    [seen] = runtime.sightings.record_receipts([detection(time.time(), 1.0, 1.0)])
    picture = await client.get(f"/sightings/{seen.id}/picture", headers=AUTH)
    assert picture.status_code == 200
    assert picture.headers["content-type"] == "image/jpeg" and picture.content == JPEG
    assert (await client.get(f"/sightings/{seen.id}/picture")).status_code == 401
    foreign = await client.get(f"/sightings/{seen.id}/picture", headers={**AUTH, "Host": "evil.example:8765"})
    assert foreign.status_code == 421 and "is not served here" in foreign.json()["detail"]


async def test_an_unknown_sighting_or_one_whose_picture_is_gone_is_404_saying_why(
    client: httpx.AsyncClient, runtime: TestRuntime, images_dir: Path
) -> None:
    [seen] = runtime.sightings.record_receipts([detection(time.time(), 1.0, 1.0)])
    unknown = await client.get(f"/sightings/{seen.id + 1}/picture", headers=AUTH)
    assert unknown.status_code == 404 and "GET /sightings lists them" in unknown.json()["detail"]
    gone = await client.get(f"/sightings/{seen.id}/picture", headers=AUTH)
    assert gone.status_code == 404 and "has no picture" in gone.json()["detail"]
    assert (await client.get("/sightings/0/picture", headers=AUTH)).status_code == 422
