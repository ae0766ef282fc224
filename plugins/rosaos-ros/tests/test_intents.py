"""intents.yaml: the offline engine's sentence templates for robots, read by core's loader."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from rosaos.intents.grammar.intents_file import IntentsFile
from rosaos.testing import IntentProbe
from rosaos_ros.plugin import SPEC

BENCH = Path(__file__).resolve().parents[4] / "shared" / "bench" / "tasks"


@pytest.fixture(scope="module")
def probe() -> IntentProbe:
    """The templates, with a turtlebot and a dog in the {device} list."""
    return IntentProbe(SPEC, devices={"turtlebot": "turtlebot", "dog": "dog", "robot dog": "dog"})


@pytest.fixture(scope="module")
def intents_file(probe: IntentProbe) -> IntentsFile:
    return probe.intents_file


@pytest.mark.parametrize(
    ("sentence", "expected"),
    [
        # The robot commands of the public bench tasks (robots.yaml, multi.yaml).
        ("Undock the turtlebot", ("turtlebot", "undock", {})),
        ("Send the turtlebot back to its dock", ("turtlebot", "dock", {})),
        ("Drive the turtlebot forward one meter", ("turtlebot", "move_distance", {"meters": 1})),
        ("Turn the turtlebot 90 degrees to the left", ("turtlebot", "rotate", {"degrees": 90})),
        ("Make the dog walk forward", ("dog", "move_distance", {"meters": 0.5})),
        # Obvious variants.
        ("dock the turtlebot", ("turtlebot", "dock", {})),
        ("take the turtlebot off the dock", ("turtlebot", "undock", {})),
        ("drive the turtlebot forward 2.5 meters", ("turtlebot", "move_distance", {"meters": 2.5})),
        ("move the turtlebot two metres forward", ("turtlebot", "move_distance", {"meters": 2})),
        ("drive the turtlebot backwards one meter", ("turtlebot", "move_distance", {"meters": -1.0})),
        ("back the turtlebot up 0.5 meters", ("turtlebot", "move_distance", {"meters": -0.5})),
        ("drive the turtlebot backwards half a meter", ("turtlebot", "move_distance", {"meters": -0.5})),
        ("make the dog walk forward half a metre", ("dog", "move_distance", {"meters": 0.5})),
        ("turn the turtlebot 45 degrees to the right", ("turtlebot", "rotate", {"degrees": -45.0})),
        ("turn the dog right by ninety degrees", ("dog", "rotate", {"degrees": -90.0})),
        ("rotate the turtlebot ninety degrees left", ("turtlebot", "rotate", {"degrees": 90})),
        ("turn the robot dog left", ("dog", "rotate", {"degrees": 90})),
        ("turn the turtlebot around", ("turtlebot", "rotate", {"degrees": 180})),
        ("stop the turtlebot", ("turtlebot", "stop", {})),
        ("dog stop", ("dog", "stop", {})),
        ("take a picture with the turtlebot", ("turtlebot", "capture_image", {})),
        ("move the turtlebot forward 50 centimeters", ("turtlebot", "move_distance", {"meters": 0.5})),
        ("drive the turtlebot back 30 cm", ("turtlebot", "move_distance", {"meters": -0.3})),
        ("make the dog walk backward", ("dog", "move_distance", {"meters": -0.5})),
        ("bring the turtlebot home", ("turtlebot", "dock", {})),
        ("turtlebot, go back to the dock", ("turtlebot", "dock", {})),
        ("spin the turtlebot around", ("turtlebot", "rotate", {"degrees": 360})),
        # Searches (a long task) and looking.
        ("make the turtlebot search the room for a person", ("turtlebot", "search", {"target": "person"})),
        ("turtlebot, look around for someone", ("turtlebot", "search", {"target": "person"})),
        ("have the turtlebot look for people in the lab", ("turtlebot", "search", {"target": "person"})),
        ("search the house for anybody with the turtlebot", ("turtlebot", "search", {"target": "person"})),
        ("send the turtlebot to find someone", ("turtlebot", "search", {"target": "person"})),
        ("does the turtlebot see anyone", ("turtlebot", "detect_people", {})),
    ],
)
def test_sentence_maps_to_tool_call(
    probe: IntentProbe, sentence: str, expected: tuple[str, str, dict[str, Any]]
) -> None:
    assert probe.match(sentence) == expected


@pytest.mark.parametrize(
    "sentence",
    ["Tell the drone to take off", "Drive the car forward one meter", "Stop the music", "Turn off the lamp"],
)
def test_other_devices_and_requests_do_not_match(probe: IntentProbe, sentence: str) -> None:
    assert probe.match(sentence) is None


@pytest.mark.parametrize(
    "sentence", ["search the environment for a person", "look for someone", "look around for a person"]
)
def test_a_search_needs_no_robot_named_when_only_one_can_search(sentence: str) -> None:
    probe = IntentProbe(SPEC, devices={"turtlebot": "turtlebot"})
    assert probe.match(sentence) == ("turtlebot", "search", {"target": "person"})


def test_left_and_right_number_words_keep_their_signs_in_any_order(probe: IntentProbe) -> None:
    # hassil caches number words per range and ignores the multiplier: the lists must not share ranges.
    right = probe.match("turn the turtlebot thirty degrees to the right")
    left = probe.match("turn the turtlebot thirty degrees to the left")
    assert (right, left) == (
        ("turtlebot", "rotate", {"degrees": -30.0}),
        ("turtlebot", "rotate", {"degrees": 30}),
    )


def test_signed_lists_do_not_share_a_range_with_positive_ones(intents_file: IntentsFile) -> None:
    ranges = {name: spec["range"] for name, spec in intents_file.hassil["lists"].items() if "range" in spec}
    key = lambda r: (r["from"], r["to"], r.get("step", 1), r.get("fractions"))  # noqa: E731
    negative = {key(r) for r in ranges.values() if r.get("multiplier", 1) < 0}
    positive = {key(r) for r in ranges.values() if r.get("multiplier", 1) > 0}
    assert not negative & positive


@pytest.mark.skipif(not BENCH.is_dir(), reason="the public bench tasks are not next to this checkout")
def test_every_robot_command_of_the_bench_matches_except_the_unknown_robot(probe: IntentProbe) -> None:
    sentences = [
        task["say"]
        for name in ("robots.yaml", "multi.yaml")
        for task in yaml.safe_load((BENCH / name).read_text(encoding="utf-8"))["tasks"]
        if any(word in task["say"].lower() for word in ("turtlebot", "dog", "drone"))
    ]
    clauses = [clause.strip() for sentence in sentences for clause in sentence.split(" and ")]
    robot_clauses = [c for c in clauses if "turtlebot" in c.lower() or "dog" in c.lower()]
    assert all(probe.match(clause) for clause in robot_clauses), robot_clauses
    assert probe.match("Tell the drone to take off") is None


@pytest.mark.parametrize(
    ("sentence", "intent"),
    [
        ("is the turtlebot docked", "RosIsDocked"),
        ("What's the turtlebot's battery level?", "RosBattery"),
        ("how much battery does the turtlebot have left", "RosBattery"),
        ("where is the robot dog", "RosWhere"),
    ],
)
def test_questions_read_the_state_and_say_what_they_found(
    probe: IntentProbe, intents_file: IntentsFile, sentence: str, intent: str
) -> None:
    match = probe.match(sentence)
    assert match is not None and (match.tool, match.args) == ("get_state", {})
    assert intents_file.actions[intent].is_question
