"""VAD segmentation: utterances are cut at the configured silence, short bursts dropped, timing kept."""

from __future__ import annotations

import numpy as np
import pytest

from rosaos.frontends.voice.sources import SAMPLE_RATE, Samples
from rosaos.frontends.voice.vad import EnergyClassifier, Segmenter, SileroClassifier, SpeechSegment

from .voice_support import chunks_of, needs_espeak, pattern, tone

FRAME = 0.03  # the energy classifier's frame


def segment(samples: Samples, chunk_seconds: float = 0.12, **settings: float) -> list[SpeechSegment]:
    segmenter = Segmenter(EnergyClassifier(-40), **settings)
    found = []
    for chunk in chunks_of(samples, chunk_seconds):
        found += segmenter.feed(chunk)
    return found + segmenter.flush()


def test_one_tone_between_silences_is_one_utterance_with_its_times() -> None:
    [utterance] = segment(pattern(("silence", 0.5), ("tone", 1.0), ("silence", 1.0)))
    assert utterance.start == pytest.approx(0.5, abs=FRAME)
    assert utterance.end == pytest.approx(1.5, abs=FRAME)
    assert utterance.duration == pytest.approx(1.0, abs=2 * FRAME)


def test_the_end_is_known_after_the_silence_threshold_within_one_chunk() -> None:
    [utterance] = segment(pattern(("tone", 1.0), ("silence", 2.0)), chunk_seconds=0.12, silence_seconds=0.55)
    assert 0.55 - FRAME <= utterance.vad_delay <= 0.55 + 0.12 + FRAME


def test_a_longer_silence_threshold_waits_longer() -> None:
    [utterance] = segment(pattern(("tone", 1.0), ("silence", 2.0)), silence_seconds=1.0)
    assert utterance.vad_delay == pytest.approx(1.0, abs=0.12 + FRAME)


def test_a_pause_shorter_than_the_threshold_does_not_split() -> None:
    found = segment(pattern(("tone", 0.6), ("silence", 0.3), ("tone", 0.6), ("silence", 1.0)))
    assert len(found) == 1
    assert found[0].duration == pytest.approx(1.5, abs=2 * FRAME)


def test_a_pause_longer_than_the_threshold_splits() -> None:
    found = segment(pattern(("tone", 0.6), ("silence", 0.8), ("tone", 0.6), ("silence", 1.0)))
    assert [round(s.start, 1) for s in found] == [0.0, 1.4]


def test_a_burst_shorter_than_the_minimum_speech_is_dropped() -> None:
    assert segment(pattern(("silence", 0.3), ("tone", 0.2), ("silence", 1.0)), min_speech_seconds=0.35) == []


def test_the_minimum_speech_length_is_configurable() -> None:
    short = pattern(("silence", 0.3), ("tone", 0.2), ("silence", 1.0))
    assert len(segment(short, min_speech_seconds=0.1)) == 1


def test_a_long_utterance_is_cut_at_the_maximum_length() -> None:
    found = segment(pattern(("tone", 2.5), ("silence", 1.0)), max_utterance_seconds=1.0)
    assert len(found) == 3
    assert all(s.duration <= 1.0 + FRAME for s in found)


def test_the_end_of_the_stream_ends_the_utterance_in_progress() -> None:
    [utterance] = segment(pattern(("silence", 0.2), ("tone", 1.0)))
    assert utterance.end == pytest.approx(1.2, abs=FRAME)


def test_silence_alone_is_no_utterance() -> None:
    assert segment(pattern(("silence", 3.0))) == []


def test_the_audio_keeps_a_little_before_and_after_the_speech() -> None:
    [utterance] = segment(pattern(("silence", 1.0), ("tone", 1.0), ("silence", 2.0)))
    seconds = utterance.samples.size / SAMPLE_RATE
    assert 1.0 + 0.2 <= seconds <= 1.0 + 0.25 + 0.3 + FRAME


def test_chunk_sizes_that_do_not_divide_frames_give_the_same_utterances() -> None:
    signal = pattern(("silence", 0.5), ("tone", 1.0), ("silence", 1.0))
    odd, even = segment(signal, chunk_seconds=0.047), segment(signal, chunk_seconds=0.12)
    assert [(s.start, s.end) for s in odd] == [(s.start, s.end) for s in even]


def test_reset_forgets_the_utterance_in_progress() -> None:
    segmenter = Segmenter(EnergyClassifier(-40))
    chunks = chunks_of(pattern(("tone", 1.0), ("silence", 1.0)))
    for chunk in chunks[:5]:
        segmenter.feed(chunk)
    assert segmenter.in_speech
    segmenter.reset()
    assert segmenter.flush() == []


def test_the_wall_clock_start_follows_the_chunks() -> None:
    [utterance] = segment(pattern(("silence", 0.5), ("tone", 1.0), ("silence", 1.0)))
    assert utterance.wall_start == pytest.approx(1_000.0 + utterance.start)


def test_silero_hears_no_speech_in_a_tone() -> None:
    segmenter = Segmenter(SileroClassifier())
    found = [s for chunk in chunks_of(tone(2.0)) for s in segmenter.feed(chunk)]
    assert found + segmenter.flush() == []


@needs_espeak
def test_silero_finds_the_spoken_sentence(spoken_command: Samples) -> None:
    padded = np.concatenate([np.zeros(8000, np.float32), spoken_command, np.zeros(16000, np.float32)])
    segmenter = Segmenter(SileroClassifier())
    found = [s for chunk in chunks_of(padded) for s in segmenter.feed(chunk)] + segmenter.flush()
    assert len(found) == 1
    assert 1.2 < found[0].duration < 2.0  # espeak says it in about 1.6 s
