"""detect_people: OpenCV's HOG and face detectors read the camera's pixels and place who they find."""

from __future__ import annotations

import io
import math
from pathlib import Path
from typing import Any

import pytest
from PIL import Image

from rosaos_ros.perception import PersonBox, find_people, place
from rosaos_ros.sim.images import FIELD_OF_VIEW, WIDTH, jpeg_bytes, render


@pytest.mark.parametrize("distance", [2.0, 3.0, 4.0, 5.0])
def test_a_person_is_found_and_their_range_estimated_from_the_box(distance: float) -> None:
    # The robot stands at (0, 1) facing +x: no pillar between it and the person.
    boxes = find_people(render(0, 1, 0, [(distance, 1.2)]))
    assert len(boxes) == 1
    where = place(boxes[0], WIDTH, FIELD_OF_VIEW, (0.0, 1.0, 0.0))
    assert where.distance == pytest.approx(distance, rel=0.2)
    assert where.bearing > 0, "a person at y=1.2 is to the left of a robot at y=1 facing +x"
    assert (where.x, where.y) == (pytest.approx(distance, abs=0.6), pytest.approx(1.2, abs=0.3))


def test_the_demonstration_person_is_placed_in_the_world_from_the_robot_pose() -> None:
    yaw = math.atan2(0.5, -2.5) - 0.2  # turned toward them, not exactly
    boxes = find_people(render(0, 0, yaw, [(-2.5, 0.5)]))
    assert [box.method for box in boxes] == ["body"]
    where = place(boxes[0], WIDTH, FIELD_OF_VIEW, (0.0, 0.0, yaw))
    assert math.hypot(where.x - -2.5, where.y - 0.5) < 0.5  # type: ignore[operator]


@pytest.mark.parametrize(("x", "y"), [(0.0, 0.0), (1.0, 1.0), (-1.0, 0.5), (0.5, -1.5)])
def test_nobody_is_found_in_an_empty_world_whichever_way_the_robot_looks(x: float, y: float) -> None:
    for step in range(12):
        frame = as_received(render(x, y, step * math.pi / 6 - math.pi))
        assert find_people(frame) == [], f"a phantom at step {step}"


def as_received(frame: Image.Image) -> Image.Image:
    """``frame`` as the driver gets it: JPEG-compressed, with its artefacts."""
    return Image.open(io.BytesIO(jpeg_bytes(frame))).convert("RGB")


def test_two_people_are_two_boxes() -> None:
    boxes = find_people(render(0, 1, 0, [(3.0, 1.7), (3.5, 0.3)]))
    assert len(boxes) == 2
    bearings = sorted(place(box, WIDTH, FIELD_OF_VIEW).bearing for box in boxes)
    assert bearings[0] < 0 < bearings[1]


def test_the_detector_reads_pixels_not_the_simulator() -> None:
    """The same frame saved and read back as a JPEG file (as from any camera) gives the same answer."""
    frame = render(0, 1, 0, [(3.0, 1.0)])
    assert len(find_people(frame)) == 1
    blank = Image.new("RGB", frame.size, (128, 128, 128))
    assert find_people(blank) == []
    big = frame.resize((1280, 960))  # a high-resolution camera: scaled down to the working width first
    assert len(boxes := find_people(big)) == 1 and boxes[0].height > 300


def test_a_face_gives_a_range_from_its_width() -> None:
    face = PersonBox(left=150, top=40, width=20, height=20, score=10, method="face")
    focal = (WIDTH / 2) / math.tan(FIELD_OF_VIEW / 2)
    assert place(face, WIDTH, FIELD_OF_VIEW).distance == pytest.approx(focal * 0.22 / 20, rel=0.05)


async def test_detect_people_over_the_driver_records_the_sighting(open_robot: Any, tmp_path: Path) -> None:
    async with open_robot(sim={"docked": False, "people": [{"x": 3.0, "y": -0.6}]}) as robot:
        assert "people_seen" not in await robot.call("get_state")
        result = await robot.call("detect_people")
        state = await robot.call("get_state")
        robot.world.reset_pose(0.0, 0.0, math.pi)
        await robot.call("get_state")  # odometry has the new pose
        behind = await robot.call("detect_people")
    assert result["found"] is True and result["count"] == 1
    person = result["people"][0]
    assert person["direction"] == "to the right" and person["bearing_deg"] < 0
    assert math.hypot(person["x"] - 3.0, person["y"] - -0.6) < 0.6
    assert (tmp_path / "images" / result["image"]).is_file()
    assert state["last_image"] == result["image"]
    [seen] = state["people_seen"]
    assert (seen["x"], seen["y"]) == (person["x"], person["y"]) and seen["at"].endswith("+00:00")
    assert behind["found"] is False and behind["people"] == []


async def test_people_seen_keeps_the_newest_twenty(open_robot: Any) -> None:
    async with open_robot(sim={"docked": False, "people": [{"x": 3.0, "y": 0.6}]}) as robot:
        for _ in range(3):
            await robot.call("detect_people")
        backend = robot.backend
        for index in range(25):
            backend.sightings.seen.append({"x": float(index), "y": 0.0, "at": "t"})
        seen = (await robot.call("get_state"))["people_seen"]
    assert len(seen) == 20 and seen[-1]["x"] == 24.0
