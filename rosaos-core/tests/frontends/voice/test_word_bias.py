"""The world's words: near misses of its long names are mended, right words are left alone, and the
decoder's bonus goes only to whole known words or continuations of their beginnings."""

from __future__ import annotations

import numpy as np
import pytest

from rosaos.frontends.voice.word_bias import Bias, world_phrases

ROBOTS = {
    "turtlebot": {"driver": "ros"},
    "dog": {"driver": "ros"},
    "living_room_lamp": {"driver": "tapo", "aliases": ["floor lamp"], "area": "living room"},
    "spotify": {
        "driver": "spotify",
        "sim": {"catalog": [{"track": "Clair de Lune", "artist": "Claude Debussy"}]},
    },
}


def test_world_phrases_hold_names_aliases_rooms_and_catalog_entries() -> None:
    phrases = world_phrases(ROBOTS)
    for expected in (
        "turtlebot",
        "living room lamp",
        "floor lamp",
        "living room",
        "Clair de Lune",
        "Claude Debussy",
    ):
        assert expected in phrases


@pytest.mark.parametrize(
    ("heard", "mended"),
    [
        ("Drive the turtle not forward one meter.", "Drive the turtlebot forward one meter."),
        ("Ah, knock the turtle, but", "Ah, knock the turtlebot"),
        ("Drive the Turtle Moth forward one meter.", "Drive the turtlebot forward one meter."),
        ("Play something by Claude Debusy", "Play something by Claude debussy"),
        # Bent into other words: matched by how they sound (consonants in order), not by letters.
        ("Send the total not back to its dock.", "Send the turtlebot back to its dock."),
        ("Turn the total button 90 degrees.", "Turn the turtlebot 90 degrees."),
        (
            "And knock the turtle out and turn the lamp blue.",
            "And knock the turtlebot and turn the lamp blue.",
        ),
        ("Play Clara blue", "Play Clair de Lune"),
    ],
)
def test_near_misses_of_long_names_are_mended(heard: str, mended: str) -> None:
    assert Bias(world_phrases(ROBOTS)).correct(heard) == mended


@pytest.mark.parametrize(
    "right",
    [
        "Turn on the living room lamp.",
        "Make the dog walk forward.",
        "Send the turtlebot back to its dock.",
        "Turn the music up and tell me a story.",
        "Turn the turtlebot 90 degrees to the left.",
        "Make the dog walk forward and play Here Comes the Sun.",
        "Set the floor lamp to warm white.",
        "Play something by Claude Debussy.",
        "Tell the drone to take off.",
        "Turn the total lights down.",
    ],
)
def test_right_sentences_are_left_alone(right: str) -> None:
    assert Bias(world_phrases(ROBOTS)).correct(right) == right


def test_the_bonus_goes_to_known_words_and_their_continuations_only() -> None:
    bias = Bias(world_phrases(ROBOTS), bonus=3.0)
    pieces = [" not", "bot", " for", " hello"]
    # "turtle" + "bot" continues a known word: it wins over the likelier " not".
    assert bias.choose(np.array([5.0, 3.0, 0.0, 0.0], np.float32), "turtle", pieces) == 1
    # " for" only begins "forward": no bonus, " hello" stays.
    assert bias.choose(np.array([0.0, 0.0, 4.0, 5.0], np.float32), "", pieces) == 3
    # A bonus never lifts a token the model finds far less likely.
    assert bias.choose(np.array([9.0, 3.0, 0.0, 0.0], np.float32), "turtle", pieces) == 0
