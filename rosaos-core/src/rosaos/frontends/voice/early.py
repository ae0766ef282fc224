"""Early transcription: start speech-to-text while the VAD still waits to be sure an utterance ended.

An utterance ends after ``silence_seconds`` (0.55 s) without speech: a shorter pause may be the
speaker drawing breath. The speech the engine gets, though, is fixed as soon as the speaker
pauses. So after a short pause (``DRAFT_SILENCE_SECONDS``) the segmenter hands out a *draft* of
the utterance (its post-roll padded with zeros), and :class:`EarlyTranscriber` starts transcribing
it at once. If the pause lasts, the final utterance has the draft's speech and its transcript is
(nearly) ready; if the speaker goes on, the draft's transcript is thrown away and the longer
utterance is transcribed as usual.

The draft's transcript is also what the pipeline judges (:mod:`rosaos.frontends.voice.end_of_turn`):
a whole command ends the turn after a short pause instead of the full ``silence_seconds``.

Only for the local engine: with a cloud engine every draft would be a request (and a bill).
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from dataclasses import dataclass

from rosaos.frontends.voice.stt import SpeechToText
from rosaos.frontends.voice.vad import SpeechSegment


@dataclass(frozen=True)
class Transcript:
    """A transcript, and how it was made."""

    text: str
    compute_seconds: float
    """How long the engine worked on it."""
    early: bool = False
    """Made from the draft, while the VAD was still waiting."""


def draft_key(segment: SpeechSegment) -> tuple[float, float]:
    """Segments with the same start and end hold the same speech (the segmenter is deterministic);
    only how much of the trailing silence is real differs, and it is silence either way."""
    return (segment.start, segment.end)


class EarlyTranscriber:
    """Transcribes drafts ahead of time; :meth:`transcribe` uses the draft's result when it fits."""

    def __init__(self, stt: SpeechToText, early: bool = True) -> None:
        self.stt = stt
        self.early = early
        self._key: tuple[float, float] | None = None
        self._task: asyncio.Task[Transcript] | None = None
        self.drafts = 0
        self.used = 0
        """Drafts whose transcript became the utterance's (the others were thrown away)."""

    def draft(self, segment: SpeechSegment) -> None:
        """The VAD's draft of an utterance that may be ending: start transcribing it now."""
        if not self.early:
            return
        self.drafts += 1
        self._key = draft_key(segment)
        self._task = asyncio.create_task(self._timed(segment), name="voice: early transcription")

    async def of_draft(self, segment: SpeechSegment) -> Transcript | None:
        """The transcript of draft ``segment`` once it is made; None if it failed or a newer draft
        replaced it (not when the final utterance took it: the pipeline reports it came too late).
        Waiting here never cancels the transcription."""
        task = self._task
        if task is None or self._key != draft_key(segment):
            return None
        try:
            result = await asyncio.shield(task)
        except Exception:  # the final utterance retries it (transcribe)
            return None
        return result if self._task is task or self._task is None else None

    async def transcribe(self, segment: SpeechSegment) -> Transcript:
        """The transcript of a final utterance: the draft's if it had the same samples, else made now."""
        task, key = self._task, self._key
        self._task = self._key = None
        if task is not None and key == draft_key(segment):
            with contextlib.suppress(Exception):  # a failed draft is retried below, as a normal one
                result = await task
                self.used += 1
                return Transcript(result.text, result.compute_seconds, early=True)
        elif task is not None:
            # The speaker went on after the draft: its transcript is stale. The engine's thread
            # cannot be interrupted; awaiting it keeps one transcription running at a time.
            with contextlib.suppress(Exception):
                await task
        return await self._timed(segment)

    def close(self) -> None:
        """Drop a draft still being transcribed (the pipeline is stopping)."""
        if self._task is not None:
            self._task.cancel()
        self._task = self._key = None

    async def _timed(self, segment: SpeechSegment) -> Transcript:
        began = time.perf_counter()
        text = await self.stt.transcribe(segment.samples)
        return Transcript(text, round(time.perf_counter() - began, 3))
