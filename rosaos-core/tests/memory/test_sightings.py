"""Sightings from tool receipts: who a robot saw, where, near which place of the same frame."""

from __future__ import annotations

import json
import time
from pathlib import Path

from rosaos.memory.sightings import SightingLog, ago
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
