"""The simulated camera: a pinhole view in which people stand where the sim settings put them."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image, ImageChops
from pydantic import ValidationError

from rosaos_ros.sim.images import FOCAL, HEIGHT, WIDTH, render
from rosaos_ros.sim.world import SimState


def person_box(
    x: float, y: float, yaw: float, people: list[tuple[float, float]]
) -> tuple[int, int, int, int] | None:
    """Where the frame differs from the same view with nobody in it: the person's pixels, or None."""
    return ImageChops.difference(render(x, y, yaw, people), render(x, y, yaw)).getbbox()


# The robot stands at (0, 1) facing +x, so no pillar stands between it and a person ahead.
def test_a_person_ahead_is_in_the_frame_upright_and_centred() -> None:
    box = person_box(0, 1, 0, [(3.0, 1.0)])
    assert box is not None
    left, top, right, bottom = box
    assert abs((left + right) / 2 - WIDTH / 2) <= 2
    assert (bottom - top) > 2.5 * (right - left)  # standing: much taller than wide
    assert bottom - top == pytest.approx(FOCAL * 1.7 / 3.0, rel=0.08)  # a 1.7 m person at 3 m


def test_a_person_twice_as_far_is_half_as_tall() -> None:
    near, far = person_box(0, 1, 0, [(2.0, 1.0)]), person_box(0, 1, 0, [(4.0, 1.0)])
    assert near is not None and far is not None
    assert (far[3] - far[1]) == pytest.approx((near[3] - near[1]) / 2, rel=0.1)


def test_a_person_to_the_left_is_on_the_left_of_the_frame() -> None:
    box = person_box(0, 1, 0, [(3.0, 2.0)])
    assert box is not None and box[2] < WIDTH / 2


@pytest.mark.parametrize(
    ("where", "why"),
    [
        ((-3.0, 0.0), "behind the robot"),
        ((0.0, 3.0), "beside it, out of the field of view"),
        ((0.05, 0.0), "at the lens"),
    ],
)
def test_a_person_out_of_view_is_not_in_the_frame(where: tuple[float, float], why: str) -> None:
    assert person_box(0, 0, 0, [where]) is None, why


def test_turning_toward_a_person_brings_them_into_view() -> None:
    person = [(-2.5, 0.5)]  # the demonstration's person, behind a robot on the origin facing +x
    assert person_box(0, 0, 0, person) is None
    assert person_box(0, 0, math.atan2(0.5, -2.5), person) is not None


def test_a_nearer_pillar_hides_the_person_behind_it() -> None:
    box = person_box(0, 0, 0, [(3.0, 0.0)])  # the red pillar at (2, 0) stands between
    assert box is not None
    frame = render(0, 0, 0, [(3.0, 0.0)])
    red = frame.getpixel((WIDTH // 2, HEIGHT // 2))
    assert red == render(0, 0, 0).getpixel((WIDTH // 2, HEIGHT // 2)), "the pillar's pixels stay in front"


def test_people_are_a_sim_setting() -> None:
    state = SimState.model_validate({"profile": "turtlebot4", "people": [{"x": -2.5, "y": 0.5}]})
    assert [(p.x, p.y) for p in state.people] == [(-2.5, 0.5)]
    with pytest.raises(ValidationError):
        SimState.model_validate({"people": [{"x": 1.0}]})
    with pytest.raises(ValidationError):
        SimState.model_validate({"people": [{"x": 1.0, "y": 0.0, "z": 2.0}]})


async def test_the_robot_camera_shows_the_person_over_rosbridge(open_robot: Any, tmp_path: Path) -> None:
    async with open_robot(sim={"docked": False, "people": [{"x": 2.5, "y": -0.6}]}) as robot:
        seen = await robot.call("capture_image")
        robot.world.reset_pose(0.0, 0.0, math.pi)  # turned around: the person is behind
        unseen = await robot.call("capture_image")
    images = tmp_path / "images"
    with Image.open(images / seen["image"]) as frame:
        assert frame.size == (WIDTH, HEIGHT)
        shirt = _count_near(frame, (196, 64, 52))
    with Image.open(images / unseen["image"]) as frame:
        assert _count_near(frame, (196, 64, 52)) == 0
    assert shirt > 200


def _count_near(frame: Image.Image, colour: tuple[int, int, int], tolerance: int = 30) -> int:
    """Pixels within ``tolerance`` of ``colour`` in every channel (JPEG shifts colours a little)."""
    pixels = np.asarray(frame.convert("RGB"), dtype=np.int16)
    return int(np.all(np.abs(pixels - np.array(colour)) <= tolerance, axis=2).sum())
