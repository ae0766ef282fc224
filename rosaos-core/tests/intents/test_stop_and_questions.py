"""Reading "stop" and state questions: a stop lexicon and question forms around device references,
not a list of sentences (:mod:`rosaos.intents.understanding.stop_words`, ``questions``)."""

from __future__ import annotations

import pytest

from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.questions import Question, read_question
from rosaos.intents.understanding.stop_words import DeviceRefs, StopRequest, read_stop

from .intents_support import home_world

WORLD = [
    *home_world(),
    DeviceVocabulary(name="dog", driver="ros", description="Hiwonder PuppyPi quadruped robot dog"),
]


@pytest.fixture(scope="module")
def refs() -> DeviceRefs:
    return DeviceRefs(WORLD)


@pytest.mark.parametrize(
    "said",
    ["stop", "Stop!", "halt", "freeze", "hold it", "stop everything", "whoa, whoa", "Oh man, stop it real quick",
     "okay, enough", "please stop now", "don't move", "emergency stop", "STOP!!!", "stop moving",
     # a remark before the stop is no command it ends: the robot stops
     "Okay, that's far enough, stop", "you've gone far enough, stop", "hmm, that's weird, stop",
     "wow okay stop", "yikes, careful, stop"],
)  # fmt: skip
def test_a_bare_stop_said_any_way_stops_everything(said: str, refs: DeviceRefs) -> None:
    assert read_stop(said, refs) == StopRequest(())


@pytest.mark.parametrize(
    ("said", "devices"),
    [
        ("stop the dog", ("dog",)),
        ("dog, stop", ("dog",)),
        ("okay, enough, halt the dog", ("dog",)),
        ("hey stop walking, dog", ("dog",)),
        ("freeze the turtlebot and the dog", ("turtlebot", "dog")),
        ("stop the robots", ("turtlebot", "dog")),
        ("stop the robot", ("turtlebot", "dog")),  # shared: a stop never waits to ask which
        ("stop the music", ("speaker",)),
        ("dog, don't move", ("dog",)),
    ],
)
def test_a_stop_that_names_devices_stops_those(said: str, devices: tuple[str, ...], refs: DeviceRefs) -> None:
    assert read_stop(said, refs) == StopRequest(devices)


@pytest.mark.parametrize(
    "said",
    ["don't stop the music", "stop at the kitchen", "walk forward then stop", "stop shuffling",
     "turn on the kitchen light", "stop following my face", "don't move the dog", "drive until you see the door and stop there"],
)  # fmt: skip
def test_sentences_that_are_not_a_stop_are_left_to_the_engine(said: str, refs: DeviceRefs) -> None:
    assert read_stop(said, refs) is None


@pytest.mark.parametrize(
    ("said", "question"),
    [
        ("is the kitchen light on?", Question("on", ("kitchen_light",))),
        ("Is the bedroom light still on?", Question("on", ("bedroom_light",))),
        ("are the lights off", Question("off", ("kitchen_light", "living_room_lamp", "bedroom_light"))),
        ("what's playing?", Question("playing", ())),
        ("where is the dog?", Question("position", ("dog",))),
        ("where is the robot", Question("position", ("turtlebot", "dog"))),
        ("how much battery?", Question("battery", ())),
        ("how charged is the turtlebot", Question("battery", ("turtlebot",))),
        ("is the turtlebot docked?", Question("docked", ("turtlebot",))),
        ("hey, can you tell me if the turtlebot is docked", Question("docked", ("turtlebot",))),
        ("does the turtlebot see anyone?", Question("people", ("turtlebot",))),
        ("what can you do?", Question("help", ())),
    ],
)
def test_state_questions_name_a_topic_and_the_devices_asked_about(
    said: str, question: Question | None, refs: DeviceRefs
) -> None:
    assert read_question(said, refs) == question


@pytest.mark.parametrize(
    ("said", "question"),
    [
        ("hmm, what can you do?", Question("help", ())),
        ("uh, is the kitchen light on?", Question("on", ("kitchen_light",))),
        ("ok so where is the dog?", Question("position", ("dog",))),
    ],
)
def test_the_discourse_around_a_question_does_not_hide_it(
    said: str, question: Question, refs: DeviceRefs
) -> None:
    assert read_question(said, refs) == question


@pytest.mark.parametrize(
    "said", ["is the kettle on?", "turn on the kitchen light", "can you turn on the light?"]
)
def test_commands_and_unknown_devices_are_not_state_questions(said: str, refs: DeviceRefs) -> None:
    assert read_question(said, refs) is None


@pytest.mark.parametrize(
    ("said", "stop"),
    [
        ("stop the dog and turn on the kitchen light", StopRequest(("dog",), "turn on the kitchen light")),
        ("turn on the kitchen light, and stop the dog", StopRequest(("dog",), "turn on the kitchen light")),
        ("stop, then turn off the lamp", StopRequest((), "turn off the lamp")),
    ],
)
def test_a_stop_among_other_commands_stops_first_and_keeps_the_rest(
    said: str, stop: StopRequest, refs: DeviceRefs
) -> None:
    assert read_stop(said, refs) == stop
