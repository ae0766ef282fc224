"""Compositional understanding, seventh round (helper lang7a). First, wrong changes: a reason or a
need said beside a complete command or a stop is no command of its own (a need once switched a
lamp on after "stop the music"), and a complaint about a setting ("whoa, that's way too loud") is a
step the other way, sized by its intensifier, never a stop of the music, while "whoa" alone still
stops. Then verbs the lexicon lacked: a learner's open and close, music put back on, vague levels
("really low", "nice and dim"). A fraction of the current level is never read as a level.
"""

from __future__ import annotations

from typing import Any

import pytest

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.vocabulary import sources_from_config
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.intents.understanding.stop_words import DeviceRefs, StopRequest, read_stop
from rosaos.plugins import load_drivers

from .intents_support import plan_calls as _calls

Call = tuple[str, str, dict[str, Any]]

_LAB = {
    "desk_lamp": DeviceConfig(driver="tapo", description="Desk lamp on the workbench"),
    "speaker": DeviceConfig(driver="spotify", description="Music on the lab speaker"),
    "dog": DeviceConfig(driver="ros", description="Hiwonder PuppyPi quadruped robot dog"),
}


@pytest.fixture(scope="module")
def lab() -> IntentMatcher:
    """One lamp, one player, one robot: a complaint has one device to be about."""
    return IntentMatcher(sources_from_config(_LAB, load_drivers()), "en")


@pytest.fixture(scope="module")
def refs() -> DeviceRefs:
    return DeviceRefs(sources_from_config(_LAB, load_drivers()))


@pytest.fixture(scope="module")
def home() -> IntentMatcher:
    """Two lights in two rooms and a player: a complaint that names no light asks which."""
    devices = {
        "living_lamp": DeviceConfig(driver="tapo", description="Floor lamp in the living room"),
        "bedroom_light": DeviceConfig(driver="tapo", description="Ceiling light in the bedroom"),
        "speaker": DeviceConfig(driver="spotify", description="Music on the kitchen speaker"),
    }
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")


# Safety first: "whoa" alone, or with a stop, still stops; a complaint after it is no stop.


@pytest.mark.parametrize(
    "said",
    [
        "whoa!",
        "whoa, stop",
        "whoa whoa",
        "woah woah woah",
        "whoa there",
        "whoa, too fast",
        "whoa whoa, way too close",
    ],
)
def test_whoa_alone_or_with_a_stop_or_a_reason_still_stops_and_does_nothing_else(
    refs: DeviceRefs, said: str
) -> None:
    assert read_stop(said, refs) == StopRequest((), "")


def test_whoa_with_a_remark_about_a_robot_stops(refs: DeviceRefs) -> None:
    assert read_stop("whoa, the dog is too close", refs) is not None


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("whoa, that's way too loud", [("speaker", "change_volume", {"delta": -40})]),
        ("whoa, the music is too loud", [("speaker", "change_volume", {"delta": -20})]),
        ("woah, way too bright", [("desk_lamp", "adjust_brightness", {"change": -40})]),
    ],
)
def test_whoa_before_a_complaint_is_a_filler_and_the_setting_steps_back(
    lab: IntentMatcher, refs: DeviceRefs, said: str, expected: list[Call]
) -> None:
    assert read_stop(said, refs) is None
    result = lab.match(said)
    assert result.kind == "plans" and _calls(result) == expected


# A reason or need beside a command or a stop: only the command


@pytest.mark.parametrize(
    ("said", "devices"),
    [
        ("stop the music please, I need to concentrate", ("speaker",)),
        ("halt the dog, time to focus", ("dog",)),
        ("stop the music, it's time to study", ("speaker",)),
        ("dog stop, I'm reading", ("dog",)),
        ("stop the music, my phone is ringing", ("speaker",)),
    ],
)
def test_a_reason_beside_a_stop_is_no_command(refs: DeviceRefs, said: str, devices: tuple[str, ...]) -> None:
    assert read_stop(said, refs) == StopRequest(devices, "")


@pytest.mark.parametrize(
    ("said", "rest"),
    [
        ("stop the dog and turn on the lamp", "turn on the lamp"),
        ("stop the dog, the music is too loud", "the music is too loud"),
        ("stop the music, I need some light to read", "i need some light to read"),
    ],
)
def test_a_command_or_a_need_that_names_a_setting_beside_a_stop_still_runs(
    refs: DeviceRefs, said: str, rest: str
) -> None:
    stop = read_stop(said, refs)
    assert stop is not None and stop.rest == rest


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("stop the music please, I need to concentrate", [("speaker", "pause", {})]),
        ("turn the music off, I'm trying to work", [("speaker", "pause", {})]),
        ("switch off the lamp, time to sleep", [("desk_lamp", "turn_off", {})]),
        ("pause it, my phone is ringing", [("speaker", "pause", {})]),
    ],
)
def test_the_matcher_also_does_only_the_command(lab: IntentMatcher, said: str, expected: list[Call]) -> None:
    result = lab.match(said)
    assert result.kind == "plans" and _calls(result) == expected


def test_a_need_alone_still_acts(lab: IntentMatcher) -> None:
    result = lab.match("I need some light to read")
    assert result.kind == "plans" and _calls(result) == [("desk_lamp", "set_brightness", {"brightness": 100})]


# A complaint about a setting: the other way, sized by the intensifier


@pytest.mark.parametrize(
    ("said", "device", "tool", "key", "sign"),
    [
        ("the music is {} loud", "speaker", "change_volume", "delta", -1),
        ("the speaker is {} quiet", "speaker", "change_volume", "delta", 1),
        ("it's {} bright in here", "desk_lamp", "adjust_brightness", "change", -1),
        ("this light is {} blue", "desk_lamp", "adjust_color_temp", "change", -1),
        ("the lamp is {} cold", "desk_lamp", "adjust_color_temp", "change", -1),
        ("the lamp looks {} yellow", "desk_lamp", "adjust_color_temp", "change", 1),
    ],
)
def test_a_complaint_steps_the_other_way_by_its_intensifier(
    lab: IntentMatcher, said: str, device: str, tool: str, key: str, sign: int
) -> None:
    steps = []
    for intensifier in ("a bit", "too", "way too"):
        [(named, used, args)] = _calls(lab.match(said.format(intensifier)))
        assert (named, used) == (device, tool)
        steps.append(args[key] * sign)
    # never a smaller step for a stronger word; a driver's own template may make "too" as small
    # as "a bit" (Spotify's "the music is too loud" is its "a bit quieter")
    assert 0 < steps[0] <= steps[1] <= steps[2] and steps[0] < steps[2], steps


def test_a_complaint_that_names_no_light_of_two_asks_which(home: IntentMatcher) -> None:
    result = home.match("ugh, it's too bright")
    assert result.kind == "clarify" and not result.processes


def test_a_complaint_names_its_light(home: IntentMatcher) -> None:
    result = home.match("the living room lamp is a little too cold")
    assert _calls(result) == [("living_lamp", "adjust_color_temp", {"change": -500})]


# Verbs the lexicon lacked


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("please open the bedroom light", [("bedroom_light", "turn_on", {})]),
        ("close the living room lamp", [("living_lamp", "turn_off", {})]),
        ("put the music back on", [("speaker", "resume", {})]),
        ("bring back the tunes", [("speaker", "resume", {})]),
        ("switch the music back on please", [("speaker", "resume", {})]),
        ("turn the bedroom light back on", [("bedroom_light", "turn_on", {})]),
    ],
)
def test_open_close_and_back_on(home: IntentMatcher, said: str, expected: list[Call]) -> None:
    result = home.match(said)
    assert result.kind == "plans" and _calls(result) == expected


def test_a_robot_brought_back_is_not_music_resumed(lab: IntentMatcher) -> None:
    assert ("speaker", "resume", {}) not in _calls(lab.match("bring the dog back"))


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("turn the volume really low", [("speaker", "set_volume", {"volume": 10})]),
        ("keep the music nice and quiet", [("speaker", "set_volume", {"volume": 25})]),
        ("make the living room lamp super bright", [("living_lamp", "set_brightness", {"brightness": 100})]),
        (
            "bedroom light on, nice and dim",
            [("bedroom_light", "turn_on", {}), ("bedroom_light", "set_brightness", {"brightness": 30})],
        ),
    ],
)
def test_a_vague_level_is_a_level(home: IntentMatcher, said: str, expected: list[Call]) -> None:
    result = home.match(said)
    assert result.kind == "plans" and _calls(result) == expected


def test_very_quiet_is_a_low_level_and_it_is_very_quiet_a_step_up(lab: IntentMatcher) -> None:
    assert _calls(lab.match("very quiet please")) == [("speaker", "set_volume", {"volume": 10})]
    assert _calls(lab.match("it's very quiet")) == [("speaker", "change_volume", {"delta": 20})]


@pytest.mark.parametrize(
    "said", ["a third louder", "cut the volume in half", "make the lamp a quarter dimmer"]
)
def test_a_share_of_the_current_level_is_never_read_as_a_level(lab: IntentMatcher, said: str) -> None:
    result = lab.match(said)
    assert not result.is_exact, _calls(result)


@pytest.mark.parametrize("said", ["it's too cold in here", "it's way too warm in here"])
def test_a_room_too_cold_is_no_light_to_change(lab: IntentMatcher, said: str) -> None:
    assert not lab.match(said).processes


@pytest.mark.parametrize("said", ["the dog is too loud", "the dog is way too bright"])
def test_a_complaint_about_a_device_that_has_no_such_setting_changes_nothing_else(
    lab: IntentMatcher, said: str
) -> None:
    assert not lab.match(said).processes
