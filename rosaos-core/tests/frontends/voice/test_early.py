"""Early transcription: the VAD's draft holds the final utterance's samples, and its transcript is
used only when the speaker really stopped."""

from __future__ import annotations

import numpy as np
import pytest

from rosaos.frontends.voice.early import EarlyTranscriber
from rosaos.frontends.voice.sources import Samples
from rosaos.frontends.voice.stt import MoonshineSTT
from rosaos.frontends.voice.vad import (
    POST_ROLL_SECONDS,
    EnergyClassifier,
    Segmenter,
    SileroClassifier,
    SpeechSegment,
)

from .voice_support import chunks_of, pattern


def segments(samples: Samples, drafts: bool = True) -> list[SpeechSegment]:
    segmenter = Segmenter(EnergyClassifier(-40), drafts=drafts)
    found: list[SpeechSegment] = []
    for chunk in chunks_of(samples):
        found += segmenter.feed(chunk)
    return found + segmenter.flush()


def test_a_draft_comes_before_the_final_with_the_same_samples() -> None:
    draft, final = segments(pattern(("silence", 0.3), ("tone", 1.0), ("silence", 1.5)))
    assert draft.draft and not final.draft
    assert np.array_equal(draft.samples, final.samples)
    assert (draft.start, draft.end) == (final.start, final.end)
    assert draft.detected_at < final.detected_at  # the point: it is there sooner


def test_a_pause_longer_than_the_post_roll_gives_a_draft_the_final_outgrows() -> None:
    found = segments(pattern(("tone", 0.6), ("silence", 0.4), ("tone", 0.6), ("silence", 1.5)))
    assert [s.draft for s in found] == [True, True, False]
    first, second, final = found
    assert first.samples.size < final.samples.size and np.array_equal(second.samples, final.samples)


def test_without_drafts_the_segmenter_is_unchanged() -> None:
    assert [s.draft for s in segments(pattern(("tone", 1.0), ("silence", 1.5)), drafts=False)] == [False]


class CountingSTT:
    """Counts what it is asked to transcribe (the engine itself is tested in test_stt.py)."""

    name = "counting"

    def __init__(self) -> None:
        self.sizes: list[int] = []

    async def transcribe(self, samples: Samples) -> str:
        self.sizes.append(int(samples.size))
        return f"{samples.size} samples"


async def test_the_drafts_transcript_is_used_when_the_speaker_stopped() -> None:
    stt = CountingSTT()
    early = EarlyTranscriber(stt)
    draft, final = segments(pattern(("tone", 1.0), ("silence", 1.5)))
    early.draft(draft)
    result = await early.transcribe(final)
    assert result.early and result.text == f"{final.samples.size} samples"
    assert stt.sizes == [final.samples.size]  # transcribed once, not twice
    assert (early.drafts, early.used) == (1, 1)


async def test_a_stale_draft_is_thrown_away() -> None:
    stt = CountingSTT()
    early = EarlyTranscriber(stt)
    first, _, final = segments(pattern(("tone", 0.6), ("silence", 0.4), ("tone", 0.6), ("silence", 1.5)))
    early.draft(first)  # the speaker went on after this one
    result = await early.transcribe(final)
    assert not result.early and result.text == f"{final.samples.size} samples"
    assert stt.sizes == [first.samples.size, final.samples.size]


async def test_switched_off_it_transcribes_only_the_final() -> None:
    stt = CountingSTT()
    early = EarlyTranscriber(stt, early=False)
    draft, final = segments(pattern(("tone", 1.0), ("silence", 1.5)))
    early.draft(draft)
    assert not (await early.transcribe(final)).early and stt.sizes == [final.samples.size]


@pytest.mark.slow  # loads the speech model and transcribes each growing draft
async def test_moonshine_on_the_draft_hears_the_whole_command(spoken_command: Samples) -> None:
    """The draft keeps the post-roll Moonshine needs: the transcript is the same as the final's."""
    segmenter = Segmenter(SileroClassifier(), drafts=True)
    audio = np.concatenate([spoken_command, np.zeros(16_000, np.float32)])
    found = [s for chunk in chunks_of(audio) for s in segmenter.feed(chunk)]
    drafts, finals = [s for s in found if s.draft], [s for s in found if not s.draft]
    assert len(finals) == 1 and drafts and np.array_equal(drafts[-1].samples, finals[0].samples)
    early = EarlyTranscriber(MoonshineSTT())
    early.draft(drafts[-1])
    result = await early.transcribe(finals[0])
    assert result.early
    assert "kitchen light" in result.text.lower()


def test_no_draft_for_a_gap_between_words() -> None:
    found = segments(pattern(("tone", 0.6), ("silence", 0.03), ("tone", 0.6), ("silence", 1.5)))
    assert [s.draft for s in found] == [True, False]  # only the real end drafts


@pytest.mark.parametrize("silence", [0.1, 0.25])
def test_a_short_pause_gives_a_draft_padded_to_the_post_roll(silence: float) -> None:
    first, second, final = segments(
        pattern(("tone", 0.6), ("silence", silence), ("tone", 0.6), ("silence", 1.5))
    )
    assert first.draft and second.draft and not final.draft
    assert first.end < second.end == final.end
    # Its post-roll is whole (zeros where the silence had not yet come): Moonshine needs it.
    assert first.samples.size >= round((first.end - first.start + POST_ROLL_SECONDS) * 16_000)
