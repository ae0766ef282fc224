"""intents.yaml: the offline engine's sentence templates for the robot, read by core's loader."""

from __future__ import annotations

from typing import Any

import pytest

from rosaos.intents.grammar.intents_file import IntentsFile
from rosaos.testing import IntentProbe
from rosaos_reachy.emotions import MoveLibrary
from rosaos_reachy.plugin import SPEC
from rosaos_reachy.settings import DANCES_DATASET, EMOTIONS_DATASET


@pytest.fixture(scope="module")
def probe() -> IntentProbe:
    """The templates, with the one robot in the {device} list."""
    return IntentProbe(SPEC, devices={"reachy": "reachy"})


@pytest.fixture(scope="module")
def intents_file(probe: IntentProbe) -> IntentsFile:
    return probe.intents_file


@pytest.mark.parametrize(
    ("sentence", "expected"),
    [
        # The Reachy tasks of the bench (../shared/bench/tasks/robots.yaml).
        ("Reachy, look to your left", ("look", {"direction": "left"})),
        ("Say good morning to everyone", ("speak", {"text": "good morning"})),
        # Other phrasings.
        ("look right", ("look", {"direction": "right"})),
        ("reachy turn your head up", ("look", {"direction": "up"})),
        ("look down reachy", ("look", {"direction": "down"})),
        ("look straight ahead", ("reset_head", {})),
        ("look at me", ("look_at_face", {})),
        ("follow my face", ("follow_face", {"on": True})),
        ("reachy keep looking at me", ("follow_face", {"on": True})),
        ("stop following my face", ("follow_face", {"on": False})),
        ("reachy say hello there", ("speak", {"text": "hello there"})),
        ("Tell everyone that dinner is ready", ("speak", {"text": "dinner is ready"})),
        ("Reachy, turn to your left", ("rotate_body", {"degrees": 45})),
        ("wake up", ("wake_up", {})),
        ("wake up reachy", ("wake_up", {})),
        ("go to sleep", ("sleep", {})),
        ("reachy time to rest", ("sleep", {})),
        ("nod", ("play_emotion", {"name": "yes"})),
        ("shake your head no", ("play_emotion", {"name": "no"})),
        ("be happy", ("play_emotion", {"name": "happy"})),
        ("look sad", ("play_emotion", {"name": "sad"})),
        ("make a surprised face", ("play_emotion", {"name": "surprised"})),
        ("be in love", ("play_emotion", {"name": "love"})),
        ("laugh", ("play_emotion", {"name": "laugh"})),
        ("dance", ("dance", {})),
        ("reachy dance for me", ("dance", {})),
        ("do the robot dance", ("dance", {"name": "robot"})),
        ("stop moving", ("stop_motion", {})),
        ("reachy stop", ("stop_motion", {})),
        ("turn your body to the left", ("rotate_body", {"degrees": 45})),
        ("turn your body back", ("rotate_body", {"degrees": 0})),
        ("take a photo", ("take_picture", {})),
        ("what do you see", ("describe_image", {})),
        ("how many people do you see", ("detect_faces", {})),
    ],
)
def test_sentence_maps_to_tool_call(
    probe: IntentProbe, sentence: str, expected: tuple[str, dict[str, Any]]
) -> None:
    assert probe.match(sentence) == ("reachy", *expected)


@pytest.mark.parametrize(
    "sentence",
    ["stop", "Tell the drone to take off", "Turn the turtlebot 90 degrees to the left", "turn on the lamp"],
)
def test_other_robots_and_bare_verbs_are_not_claimed(probe: IntentProbe, sentence: str) -> None:
    assert probe.match(sentence) is None


def test_every_emotion_and_dance_in_the_lists_exists(intents_file: IntentsFile) -> None:
    moves = MoveLibrary(EMOTIONS_DATASET, DANCES_DATASET)
    lists = intents_file.hassil["lists"]
    for kind, key in (("emotions", "emotion"), ("dances", "dance")):
        for value in lists[key]["values"]:
            name = value["out"] if isinstance(value, dict) else value
            assert moves.resolve(kind, str(name)).spec is not None, name
