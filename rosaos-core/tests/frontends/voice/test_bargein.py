"""Barge-in's echo gate: the robot's own voice never stops it; the user talking over it does."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rosaos.frontends.voice.bargein import SILENCE_DB, BargeIn, BargeInSettings, level_db
from rosaos.frontends.voice.sources import SAMPLE_RATE, Samples, read_wav
from rosaos.frontends.voice.vad import SileroClassifier

from .voice_support import chunks_of, needs_espeak, silence, speak

pytestmark = needs_espeak
ROBOT_SAYS = "Here is the weather for the whole week, day by day, starting with Monday morning."


def scaled(samples: Samples, peak: float) -> Samples:
    return (samples * (peak / float(np.max(np.abs(samples))))).astype(np.float32)


@pytest.fixture(scope="module")
def robot_voice(tmp_path_factory: pytest.TempPathFactory) -> Samples:
    """The robot's sentence as the microphones hear it: its own speaker, a little quieter."""
    return scaled(read_wav(speak(ROBOT_SAYS, tmp_path_factory.mktemp("echo") / "robot.wav")), 0.05)


@pytest.fixture(scope="module")
def user_voice(tmp_path_factory: pytest.TempPathFactory) -> Samples:
    return scaled(
        read_wav(speak("turn on the kitchen light", tmp_path_factory.mktemp("user") / "u.wav")), 0.6
    )


def first_barge_in(gate: BargeIn, samples: Samples) -> float | None:
    """Stream seconds of the end of the chunk in which the gate fired, or None."""
    gate.start()
    for chunk in chunks_of(samples):
        if gate.feed(chunk):
            return chunk.start + chunk.samples.size / SAMPLE_RATE
    return None


def test_levels_are_dbfs() -> None:
    assert level_db(np.zeros(512, np.float32)) == SILENCE_DB
    assert level_db(np.full(512, 0.5, np.float32)) == pytest.approx(-6.02, abs=0.01)


def test_the_robots_own_voice_never_barges_in(robot_voice: Samples) -> None:
    assert first_barge_in(BargeIn(SileroClassifier()), robot_voice) is None


def test_the_robots_voice_at_full_volume_does_not_either(robot_voice: Samples) -> None:
    loud = scaled(robot_voice, 0.9)  # a loud speaker next to the microphones: still its own voice
    assert first_barge_in(BargeIn(SileroClassifier()), loud) is None


def test_the_user_talking_over_the_robot_barges_in_quickly(robot_voice: Samples, user_voice: Samples) -> None:
    begins = 2.0
    mixed = robot_voice.copy()
    at = round(begins * SAMPLE_RATE)
    mixed[at : at + user_voice.size] += user_voice[: mixed.size - at]
    gate = BargeIn(SileroClassifier())
    fired = first_barge_in(gate, mixed)
    assert fired is not None and gate.onset is not None
    assert begins - 0.1 <= gate.onset <= begins + 0.3  # espeak's first consonant is soft
    assert fired - begins < 0.5  # timing is the benchmark's business; this only bounds it loosely
    kept = gate.take()
    assert kept[0].start <= gate.onset - 0.25  # the segmenter gets the onset, with pre-roll


def test_a_user_no_louder_than_the_echo_does_not(robot_voice: Samples, user_voice: Samples) -> None:
    mixed = robot_voice.copy()
    at = 2 * SAMPLE_RATE
    quiet = scaled(user_voice, 0.05)
    mixed[at : at + quiet.size] += quiet[: mixed.size - at]
    assert first_barge_in(BargeIn(SileroClassifier(), BargeInSettings(margin_db=10.0)), mixed) is None


def test_speech_after_silence_barges_in_when_the_robot_is_inaudible(user_voice: Samples) -> None:
    """No echo at all (file output, or a headset): any speech is the user's."""
    samples = np.concatenate([silence(1.0), user_voice])
    gate = BargeIn(SileroClassifier())
    assert first_barge_in(gate, samples) is not None
    assert gate.onset == pytest.approx(1.0, abs=0.3)


def test_start_forgets_the_last_stretch(tmp_path: Path, user_voice: Samples) -> None:
    gate = BargeIn(SileroClassifier())
    assert first_barge_in(gate, np.concatenate([silence(1.0), user_voice])) is not None
    gate.start()
    assert gate.take() == [] and gate.onset is None and gate.echo_db == SILENCE_DB


@pytest.mark.parametrize("words", ["stop, I have a question", "wait", "no, that is not what I asked"])
def test_the_users_first_syllables_do_not_raise_the_bar(
    robot_voice: Samples, words: str, tmp_path: Path
) -> None:
    """A user 20 dB over the echo: their first syllables, which the VAD is slow to call speech,
    and their quieter ones are not learnt as echo, or the bar would climb above their voice."""
    user = scaled(read_wav(speak(words, tmp_path / "user.wav")), 0.05 * 10 ** (20 / 20))
    mixed = robot_voice.copy()
    at = 2 * SAMPLE_RATE
    mixed[at : at + user.size] += user[: mixed.size - at]
    gate = BargeIn(SileroClassifier())
    assert first_barge_in(gate, mixed) is not None, f"echo learnt up to {gate.echo_db:.1f} dB"
    assert gate.onset is not None and 1.95 <= gate.onset <= 2.3
