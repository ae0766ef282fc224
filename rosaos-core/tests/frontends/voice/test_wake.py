"""Wake: the phrase on the transcript's start, aliases, the follow-up window, and eye contact."""

from __future__ import annotations

import numpy as np
import pytest

from rosaos.frontends.voice.wake import (
    EyeContact,
    WakeGate,
    is_noise,
    normalize,
    strip_wake_phrase,
)


def test_normalize_drops_case_punctuation_and_accents() -> None:
    assert normalize("Hello. Turn on the KITCHEN light!") == "hello turn on the kitchen light"
    assert normalize("Héllo, it's   me…") == "hello it's me"


@pytest.mark.parametrize(
    "transcript", ["", "  ", "...", "[BLANK_AUDIO]", "(music)", "*coughs*", "Um.", "uh, hmm"]
)
def test_noise_only_transcripts_are_noise(transcript: str) -> None:
    assert is_noise(transcript)


@pytest.mark.parametrize("transcript", ["Turn on the light.", "no", "[music] play jazz"])
def test_transcripts_with_words_are_not_noise(transcript: str) -> None:
    assert not is_noise(transcript)


def test_the_wake_phrase_is_stripped_from_the_command() -> None:
    assert strip_wake_phrase("Hello. Turn on the kitchen light.", ["hello"]) == "Turn on the kitchen light."
    assert strip_wake_phrase("hello turn on the kitchen light", ["hello"]) == "turn on the kitchen light"


def test_the_wake_phrase_must_be_a_whole_word_at_the_start() -> None:
    assert strip_wake_phrase("Hellos are nice", ["hello"]) is None
    assert strip_wake_phrase("I said hello", ["hello"]) is None


def test_the_longest_matching_phrase_wins() -> None:
    assert strip_wake_phrase("Hey, Rosa! Lights off.", ["hey", "hey rosa"]) == "Lights off."


def test_the_wake_phrase_alone_wakes_without_a_command() -> None:
    gate = WakeGate(phrase="hello", follow_up_seconds=8)
    decision = gate.decide("Hello.", 0.0, 0.5)
    assert (decision.action, decision.woke) == ("woke", True)
    assert gate.awake_until == 8.5


def test_wake_phrase_and_command_in_one_breath_is_a_command() -> None:
    decision = WakeGate(phrase="hello").decide("Hello. Turn on the kitchen light.", 0.0, 1.6)
    assert (decision.action, decision.command, decision.woke) == (
        "command",
        "Turn on the kitchen light.",
        True,
    )


def test_an_alias_wakes_too() -> None:
    decision = WakeGate(phrase="hello", aliases=["hey rosa"]).decide("Hey Rosa, lights off", 0, 1)
    assert (decision.action, decision.command) == ("command", "lights off")


def test_without_the_wake_phrase_speech_is_ignored() -> None:
    decision = WakeGate(phrase="hello").decide("Turn on the kitchen light.", 0, 1)
    assert decision.action == "ignored"
    assert "hello" in decision.reason


def test_a_follow_up_within_the_window_needs_no_wake_phrase() -> None:
    gate = WakeGate(phrase="hello", follow_up_seconds=8)
    gate.decide("Hello.", 0.0, 0.5)
    decision = gate.decide("Turn on the kitchen light.", 3.0, 4.5)
    assert (decision.action, decision.command, decision.woke) == (
        "command",
        "Turn on the kitchen light.",
        False,
    )
    assert decision.reason == "follow-up window"


def test_each_command_extends_the_window() -> None:
    gate = WakeGate(phrase="hello", follow_up_seconds=8)
    gate.decide("Hello, lights on.", 0.0, 1.0)
    gate.decide("And the lamp.", 7.0, 8.0)
    assert gate.decide("Dim it a bit.", 15.0, 16.0).action == "command"


def test_after_the_window_the_wake_phrase_is_needed_again() -> None:
    gate = WakeGate(phrase="hello", follow_up_seconds=8)
    gate.decide("Hello.", 0.0, 0.5)
    assert gate.decide("Turn on the kitchen light.", 9.0, 10.0).action == "ignored"
    assert gate.decide("Hello, turn on the kitchen light.", 20.0, 21.0).woke


def test_a_zero_window_means_every_command_needs_the_phrase() -> None:
    gate = WakeGate(phrase="hello", follow_up_seconds=0)
    gate.decide("Hello.", 0.0, 0.5)
    assert gate.decide("Lights on.", 1.0, 2.0).action == "ignored"


def test_wake_off_sends_everything() -> None:
    decision = WakeGate(mode="off").decide("Turn on the kitchen light.", 0, 1)
    assert (decision.action, decision.command) == ("command", "Turn on the kitchen light.")


class FakeFaces:
    """Says there is a face in frames whose first pixel is non-zero."""

    def has_face(self, frame: np.ndarray) -> bool:
        return bool(frame.flat[0])


FACE = np.ones((4, 4, 3), np.uint8)
NO_FACE = np.zeros((4, 4, 3), np.uint8)


def test_eye_contact_needs_n_consecutive_frames() -> None:
    eyes = EyeContact(FakeFaces(), frames_needed=3)
    assert [eyes.observe(f) for f in (FACE, FACE, NO_FACE, FACE, FACE, FACE, FACE)] == [
        False,
        False,
        False,
        False,
        False,
        True,
        True,
    ]


def test_eye_contact_opens_the_follow_up_window() -> None:
    gate = WakeGate(mode="eye_contact", follow_up_seconds=8)
    assert gate.decide("Turn on the kitchen light.", 0.0, 1.0).action == "ignored"
    assert gate.open(2.0) is True
    assert gate.decide("Turn on the kitchen light.", 3.0, 4.0).action == "command"


def test_in_eye_contact_mode_the_phrase_alone_does_not_wake() -> None:
    gate = WakeGate(mode="eye_contact", phrase="hello")
    assert gate.decide("Hello, turn on the light.", 0.0, 1.0).action == "ignored"


def test_either_mode_wakes_on_the_phrase_or_the_eyes() -> None:
    gate = WakeGate(mode="either", phrase="hello", follow_up_seconds=8)
    assert gate.decide("Hello, lights on.", 0.0, 1.0).action == "command"
    gate.open(20.0)
    assert gate.decide("Lights off.", 21.0, 22.0).action == "command"


def test_the_haar_detector_loads_and_sees_no_face_in_a_blank_frame() -> None:
    pytest.importorskip("cv2", reason="OpenCV is optional: eye-contact wake only")
    from rosaos.frontends.voice.wake import HaarFaceDetector

    assert HaarFaceDetector().has_face(np.zeros((240, 320, 3), np.uint8)) is False
