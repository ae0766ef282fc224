"""intents.yaml: the offline engine's sentence templates for the player, read by core's loader."""

from __future__ import annotations

from typing import Any

import pytest

from rosaos.intents.grammar.intents_file import IntentsFile
from rosaos.testing import IntentProbe
from rosaos_spotify.catalog import KNOWN_GENRES
from rosaos_spotify.plugin import SPEC


@pytest.fixture(scope="module")
def probe() -> IntentProbe:
    """The templates, with the {device} list the engine fills for the demo instance.

    Its name, and "music" read off the description "Music on the living room speaker".
    """
    return IntentProbe(SPEC, devices={"spotify": "spotify", "music": "spotify"})


@pytest.fixture(scope="module")
def intents_file(probe: IntentProbe) -> IntentsFile:
    return probe.intents_file


@pytest.mark.parametrize(
    ("sentence", "expected"),
    [
        # The music tasks of the bench (../shared/bench/tasks/home.yaml and multi.yaml).
        ("Play Clair de Lune", ("play", {"query": "Clair de Lune"})),
        ("Pause the music", ("pause", {})),
        ("Set the volume to 70", ("set_volume", {"volume": 70})),
        ("Turn the music up", ("change_volume", {"delta": 15})),
        ("Skip to the next song", ("next_track", {})),
        ("play some jazz", ("play", {"query": "jazz"})),
        ("play Here Comes the Sun", ("play", {"query": "Here Comes the Sun"})),
        ("Stop the music", ("pause", {})),
        ("turn off the music", ("pause", {})),
        ("switch spotify off", ("pause", {})),
        # Other phrasings, with and without the device's name.
        ("play Take Five on spotify", ("play", {"query": "Take Five"})),
        ("put on a little classical music", ("play", {"query": "classical"})),
        ("pause spotify", ("pause", {})),
        ("resume the music", ("resume", {})),
        ("play some music", ("resume", {})),
        ("play the previous song", ("previous_track", {})),
        ("go back", ("previous_track", {})),
        ("skip this song", ("next_track", {})),
        ("turn it down", ("change_volume", {"delta": -15})),
        ("turn the volume up by 20 percent", ("change_volume", {"delta": 20})),
        ("turn the music down by 10", ("change_volume", {"delta": -10})),
        ("set the spotify volume to 30%", ("set_volume", {"volume": 30})),
        ("shuffle on", ("set_shuffle", {"shuffle": True})),
        ("turn off shuffle", ("set_shuffle", {"shuffle": False})),
        ("repeat this song", ("set_repeat", {"repeat": "track"})),
        ("repeat the album", ("set_repeat", {"repeat": "context"})),
        ("stop repeating", ("set_repeat", {"repeat": "off"})),
        ("add Take Five to the queue", ("queue", {"query": "Take Five"})),
        ("play Bohemian Rhapsody next", ("queue", {"query": "Bohemian Rhapsody"})),
    ],
)
def test_sentence_maps_to_tool_call(
    probe: IntentProbe, sentence: str, expected: tuple[str, dict[str, Any]]
) -> None:
    assert probe.match(sentence) == ("spotify", *expected)


@pytest.mark.parametrize("sentence", ["Turn on the kitchen light", "Is the music on?", "stop"])
def test_other_devices_questions_and_bare_stop_do_not_match(probe: IntentProbe, sentence: str) -> None:
    # "stop" alone may be meant for a robot: the player must not claim it.
    assert probe.match(sentence) is None


def test_genre_list_holds_exactly_the_known_genres(intents_file: IntentsFile) -> None:
    values = [v if isinstance(v, str) else v["in"] for v in intents_file.hassil["lists"]["genre"]["values"]]
    assert values == list(KNOWN_GENRES)


def test_home_assistant_media_intents_are_mapped(intents_file: IntentsFile) -> None:
    mapping = intents_file.homeassistant
    assert mapping is not None
    assert mapping.domain == "media_player"
    tools = {name: [action.tool for action in intent.actions] for name, intent in mapping.intents.items()}
    assert tools == {
        "HassTurnOff": ["pause"],
        "HassTurnOn": ["resume"],
        "HassMediaPause": ["pause"],
        "HassMediaUnpause": ["resume"],
        "HassMediaNext": ["next_track"],
        "HassMediaPrevious": ["previous_track"],
        "HassMediaSearchAndPlay": ["play"],
        "HassSetVolume": ["set_volume"],
        "HassSetVolumeRelative": ["change_volume", "change_volume"],
    }


def test_volume_steps_map_up_and_down(intents_file: IntentsFile) -> None:
    assert intents_file.homeassistant is not None
    actions = intents_file.homeassistant.intents["HassSetVolumeRelative"].actions
    up = [a.fill({}) for a in actions if a.applies({"volume_step": "up"})]
    down = [a.fill({}) for a in actions if a.applies({"volume_step": "down"})]
    assert (up, down) == ([{"delta": 15}], [{"delta": -15}])


@pytest.mark.parametrize(
    ("sentence", "intent"),
    [
        ("What's playing?", "SpotifyWhatIsPlaying"),
        ("what song is this", "SpotifyWhatIsPlaying"),
        ("Is the music playing?", "SpotifyIsPlaying"),
        ("what's the volume", "SpotifyWhatVolume"),
    ],
)
def test_questions_read_the_state_and_say_what_they_found(
    probe: IntentProbe, intents_file: IntentsFile, sentence: str, intent: str
) -> None:
    assert probe.match(sentence) == ("spotify", "get_state", {})
    assert intents_file.actions[intent].is_question
