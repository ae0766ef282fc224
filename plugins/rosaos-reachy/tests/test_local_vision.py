"""describe_image with no vision model: people, faces, colours and brightness, computed locally."""

from __future__ import annotations

import numpy as np

from rosaos_reachy.local_vision import brightness, count_people, describe_locally, dominant_colours


def picture(
    top_bgr: tuple[int, int, int], bottom_bgr: tuple[int, int, int], top_rows: int = 180
) -> np.ndarray:
    image = np.zeros((240, 320, 3), np.uint8)
    image[:top_rows] = top_bgr
    image[top_rows:] = bottom_bgr
    return image


def test_dominant_colours_are_named_with_their_share() -> None:
    colours = dominant_colours(picture((200, 80, 40), (40, 40, 200)))  # BGR: blue over red
    assert [name for name, _ in colours[:2]] == ["blue", "red"]
    assert abs(colours[0][1] - 0.75) < 0.03


def test_brightness_goes_from_dark_to_bright() -> None:
    assert brightness(picture((0, 0, 0), (0, 0, 0))) == 0
    assert brightness(picture((255, 255, 255), (255, 255, 255))) == 1


def test_an_empty_room_has_no_people() -> None:
    assert count_people(picture((190, 190, 190), (100, 110, 120))) == 0


def test_the_description_says_what_it_found_and_that_a_model_would_say_more() -> None:
    text = describe_locally(picture((20, 20, 20), (20, 20, 20)), ["Eileen", None])
    assert "I see 2 faces (Eileen)" in text
    assert "black" in text and "dark" in text
    assert text.endswith("for any OpenAI-compatible vision endpoint.")
    assert "no one" in describe_locally(picture((240, 240, 240), (240, 240, 240)), [])
