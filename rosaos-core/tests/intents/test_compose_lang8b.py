"""Compositional understanding, eighth round (helper lang8b): a state question with an alternative
("… or did someone turn it off?") or a verb the forms lacked ("where did it end up?", "is the music
still going?"), answered from state; small talk answered in one line with nothing moved, and
"what can you do?" after a lead-in; a remark to a robot before its command; a kind of device the
world lacks inside "tell the X to …", refused and never spoken.
"""

from __future__ import annotations

import pytest

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.vocabulary import sources_from_config
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.intents.understanding.questions import Question, read_question
from rosaos.intents.understanding.small_talk import read_small_talk
from rosaos.intents.understanding.stop_words import DeviceRefs
from rosaos.plugins import load_drivers

from .intents_support import plan_calls as _calls

DEVICES = {
    "reachy": DeviceConfig(driver="reachy", description="Reachy Mini desktop robot"),
    "dog": DeviceConfig(driver="ros", description="Hiwonder PuppyPi quadruped robot dog"),
    "turtlebot": DeviceConfig(
        driver="ros", description="TurtleBot4 wheeled mobile robot with a charging dock"
    ),
    "porch_light": DeviceConfig(driver="tapo", description="Light on the porch"),
    "speaker": DeviceConfig(driver="spotify", description="Music on the living room speaker"),
}


@pytest.fixture(scope="module")
def lab() -> IntentMatcher:
    return IntentMatcher(sources_from_config(DEVICES, load_drivers()), "en")


@pytest.fixture(scope="module")
def refs() -> DeviceRefs:
    return DeviceRefs(sources_from_config(DEVICES, load_drivers()))


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("is the porch light still on or did somebody switch it off?", Question("on", ("porch_light",))),
        ("is the dog still walking, or has it stopped?", Question("busy", ("dog",))),
        ("is the turtlebot docked or is it driving around?", Question("docked", ("turtlebot",))),
        ("where did the turtlebot end up?", Question("position", ("turtlebot",))),
        ("where has the dog wound up?", Question("position", ("dog",))),
        ("is the music still going?", Question("is_playing", ())),
        ("is the speaker still going?", Question("is_playing", ("speaker",))),
        ("I'm new here, what kind of things can you do?", Question("help", ())),
    ],
)
def test_a_question_with_an_alternative_asks_its_first(
    said: str, expected: Question, refs: DeviceRefs
) -> None:
    assert read_question(said, refs) == expected


@pytest.mark.parametrize(
    ("said", "kind"),
    [
        ("hi there, how's it going?", "greeting"),
        ("good morning! how are you today?", "greeting"),
        ("hey Reachy, good morning", "greeting"),
        ("thanks so much, that's perfect", "thanks"),
        ("thank you Reachy, you've been super helpful", "thanks"),
        ("cheers dog, well done", "thanks"),
        ("bye for now, see you tomorrow", "goodbye"),
        ("good night turtlebot", "goodbye"),
    ],
)
def test_small_talk_is_answered(said: str, kind: str, refs: DeviceRefs) -> None:
    assert read_small_talk(said, lambda word: refs.resolve(word) is not None) == kind


@pytest.mark.parametrize(
    "said",
    [
        "thanks, now turn off the porch light",
        "hi, is the dog walking?",
        "hello lamp maker",
        "ok",
        "great, play jazz",
    ],
)
def test_anything_else_in_it_makes_it_not_small_talk(said: str, refs: DeviceRefs) -> None:
    assert read_small_talk(said, lambda word: refs.resolve(word) is not None) is None


@pytest.mark.parametrize(
    ("said", "device", "tool"),
    [
        ("Reachy, you look tired, go to sleep", "reachy", "sleep"),
        ("reachy, you seem sleepy, go to sleep now", "reachy", "sleep"),
        ("dog, you've been good, walk forward", "dog", "move_distance"),
        ("turtlebot, you look worn out, go back to the dock", "turtlebot", "dock"),
        ("reachy, you were great today, look to the left", "reachy", "look"),
    ],
)
def test_a_remark_to_the_robot_before_its_command_is_dropped(
    said: str, device: str, tool: str, lab: IntentMatcher
) -> None:
    result = lab.match(said)
    assert result.is_exact, result.reply
    assert [(d, t) for d, t, _ in _calls(result)] == [(device, tool)]


@pytest.mark.parametrize(
    ("said", "kind"),
    [
        ("tell the robot arm to pick up the red cup", "arm"),
        ("tell the robotic arm to grab the blue mug", "robotic arm"),
        ("ask the drone to fly over the garden", "drone"),
        ("tell the vacuum to clean the kitchen", "vacuum"),
    ],
)
def test_tell_a_kind_the_world_lacks_is_refused_never_spoken(
    said: str, kind: str, lab: IntentMatcher
) -> None:
    result = lab.match(said)
    assert not result.processes
    assert result.refusal and result.reply is not None
    assert f"no {kind}" in result.reply and "reachy" in result.reply
