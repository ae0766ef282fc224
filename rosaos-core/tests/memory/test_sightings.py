"""Sightings from tool receipts: who a robot saw, where, near which place of the same frame."""

from __future__ import annotations

import json
import time
from pathlib import Path

from rosaos.memory.sightings import SightingLog, ago, picture_path
from rosaos.memory.store import MemoryStore, Place
from rosaos.receipts import Receipt

MAP = "map:/maps/home.yaml"


def detect_receipt(people: list[dict[str, object]], started: float | None = None) -> Receipt:
    result = {"found": bool(people), "count": len(people), "people": people, "image": "turtlebot/1.jpg"}
    return Receipt(device="turtlebot", tool="detect_people", ok=True, result=json.dumps(result),
                   started=started or time.time(), duration=0.4)  # fmt: skip


def log_with_living_room(tmp_path: Path) -> SightingLog:
    store = MemoryStore.open(tmp_path)
    store.save_place(Place(name="the living room", device="turtlebot", frame="map", anchor=MAP, x=3, y=1,
                           saved_at=time.time()))  # fmt: skip
    return SightingLog(store)


def test_a_person_found_is_kept_with_the_nearest_place_of_the_same_frame_and_the_picture(
    tmp_path: Path,
) -> None:
    log = log_with_living_room(tmp_path)
    log.record_receipts([detect_receipt([{"x": 3.2, "y": 1.1, "frame": "map", "anchor": MAP}])])
    [seen] = log.recent()
    assert (seen.device, seen.place, seen.image) == ("turtlebot", "the living room", "turtlebot/1.jpg")
    assert log.recent(place="the living room") == [seen]


def test_a_sighting_in_another_frame_is_near_no_place(tmp_path: Path) -> None:
    log = log_with_living_room(tmp_path)
    log.record_receipts([detect_receipt([{"x": 3.0, "y": 1.0, "frame": "odom", "anchor": "odom:dog:abc"}])])
    assert [s.place for s in log.recent()] == [None]


def test_nobody_found_failed_calls_and_other_tools_record_nothing(tmp_path: Path) -> None:
    log = log_with_living_room(tmp_path)
    failed = Receipt(
        device="turtlebot", tool="detect_people", ok=False, error="no camera", started=0, duration=0
    )
    other = Receipt(device="turtlebot", tool="get_state", ok=True, result='{"people": [{"x": 1}]}', started=0,
                    duration=0)  # fmt: skip
    assert log.record_receipts([detect_receipt([]), failed, other]) == []


def test_sightings_older_than_the_kept_days_are_dropped_and_forget_clears(tmp_path: Path) -> None:
    log = log_with_living_room(tmp_path)
    log.keep_days = 1
    log.record_receipts([detect_receipt([{"x": 0, "y": 0}], started=time.time() - 3 * 86400)])
    log.record_receipts([detect_receipt([{"x": 0, "y": 0}])])
    assert len(log.recent()) == 1
    assert log.clear() == 1 and log.recent() == []


def test_ago_reads_as_people_say_it() -> None:
    now = 1_000_000.0
    assert [ago(now - s, now) for s in (5, 240, 7200, 3 * 86400)] == [
        "just now", "4 minutes ago", "2 hours ago", "3 days ago"
    ]  # fmt: skip


def faces_receipt(count: int, path: str = "reachy-20260101-120000-001.jpg") -> Receipt:
    """A Reachy's ``detect_faces`` result, as its FacesReport: boxes in pixels, not positions."""
    face = {"x": 310, "y": 120, "width": 90, "height": 90, "center": [0.1, -0.2], "looks_like": None}
    result = {"path": path, "count": count, "faces": [face] * count, "remembered": [], "note": "Haar"}
    return Receipt(device="reachy", tool="detect_faces", ok=True, result=json.dumps(result),
                   started=time.time(), duration=0.2)  # fmt: skip


def test_a_face_the_reachy_saw_is_kept_where_it_stands_near_the_place_on_the_floor_map(
    tmp_path: Path,
) -> None:
    store = MemoryStore.open(tmp_path)
    # The turtlebot's frame starts at (1, 0) on the floor map: its (3, 1) is (4, 1) there.
    store.save_place(Place(name="the living room", device="turtlebot", frame="map", anchor=MAP, x=3, y=1,
                           saved_at=time.time()))  # fmt: skip
    store.save_place(Place(name="the hall", device="turtlebot", frame="map", anchor=MAP, x=-4, y=0,
                           saved_at=time.time()))  # fmt: skip
    log = SightingLog(store, origins={"reachy": (4.5, 2.0, 0.0), "turtlebot": (1.0, 0.0, 0.0)})
    [face] = log.record_receipts([faces_receipt(1)])
    assert (face.what, face.device, face.frame, face.x, face.y) == ("face", "reachy", "fixed", 0.0, 0.0)
    assert (face.place, face.image) == ("the living room", "reachy-20260101-120000-001.jpg")
    assert log.get(face.id) == face and log.recent() == [face]


def test_a_face_of_a_reachy_without_a_map_origin_is_kept_but_not_placed(tmp_path: Path) -> None:
    log = log_with_living_room(tmp_path)
    [face] = log.record_receipts([faces_receipt(1)])
    assert (face.x, face.y, face.place) == (None, None, None)  # never the face's pixel box
    assert face.image == "reachy-20260101-120000-001.jpg"


def test_each_face_is_one_sighting_and_no_face_is_none(tmp_path: Path) -> None:
    log = log_with_living_room(tmp_path)
    assert log.record_receipts([faces_receipt(0)]) == []
    assert len(log.record_receipts([faces_receipt(2)])) == 2


def test_the_picture_of_a_sighting_is_a_file_inside_the_images_folder_only(tmp_path: Path) -> None:
    images = tmp_path / "images"
    images.mkdir()
    (images / "reachy-1.jpg").write_bytes(b"\xff\xd8jpeg")
    (tmp_path / "secret.jpg").write_bytes(b"not for the page")
    (images / "link.jpg").symlink_to(tmp_path / "secret.jpg")
    (images / "notes.txt").write_text("not a picture")
    assert picture_path(images, "reachy-1.jpg") == images / "reachy-1.jpg"
    for refused in ("../secret.jpg", str(tmp_path / "secret.jpg"), "link.jpg", "notes.txt", "gone.jpg"):
        assert picture_path(images, refused) is None, refused
    log = SightingLog(MemoryStore.open(tmp_path), images_dir=images)
    without, with_picture = log.record_receipts(
        [faces_receipt(1, "gone.jpg"), faces_receipt(1, "reachy-1.jpg")]
    )
    assert log.picture(with_picture) == images / "reachy-1.jpg" and log.picture(without) is None
    assert log.with_picture() == with_picture
