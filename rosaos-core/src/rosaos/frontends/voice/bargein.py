"""Barge-in: the user talks over the robot, and the robot stops talking to listen.

While the robot speaks, the pipeline does not give the audio to the segmenter (the robot would
hear itself and answer its own words). It gives it to :class:`BargeIn` instead, which keeps the
robot's own voice out with an echo gate: a frame counts as the user's only when the VAD calls it
speech *and* it is louder, by ``margin_db``, than the loudest the robot's voice has been at the
microphones over the last ``echo_window_seconds``. ``min_speech_seconds`` of such frames in a row
is a barge-in. The first ``learn_seconds`` of each stretch of robot speech only teach the gate
how loud the echo is; after that, a frame teaches it only when nothing loud enough to be the user
came in the :data:`LEARN_HOLD_SECONDS` before (else the user's own first syllables, which the
VAD is slow to call speech, and quieter ones would raise the bar above their voice).

A microphone array with its own echo cancellation (one that subtracts what its speaker plays)
makes the echo much quieter, so a normal voice barges in; without one the user has to speak up
over the robot. Either way the robot never interrupts itself: its voice sets the bar.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from rosaos.frontends.voice.sources import SAMPLE_RATE, AudioChunk, Samples
from rosaos.frontends.voice.vad import FrameClassifier

SILENCE_DB = -120.0
"""The level of digital silence (an all-zero frame), instead of minus infinity."""
LEARN_HOLD_SECONDS = 0.3
"""Frames within this long after one loud enough to be the user are not learnt as echo."""
ECHO_RISE_DB_PER_SECOND = 40.0
"""After the first ``learn_seconds``, how fast the echo's learnt level may climb."""
KEEP_SECONDS = 1.0
"""Audio kept while the robot speaks, handed on at a barge-in: the onset of what the user says."""


def level_db(frame: Samples) -> float:
    """Loudness of a frame in dBFS (RMS)."""
    if frame.size == 0:
        return SILENCE_DB
    rms = float(np.sqrt(np.mean(np.square(frame, dtype=np.float64))))
    return max(SILENCE_DB, 20.0 * float(np.log10(max(rms, 1e-12))))


@dataclass(frozen=True)
class BargeInSettings:
    """How eager barge-in is; ``[voice] barge_in_*`` in the config."""

    margin_db: float = 10.0
    """The user must be this much louder than the robot's echo at the microphones."""
    min_speech_seconds: float = 0.1
    """Speech above the echo for this long, in a row, is a barge-in (a cough is shorter)."""
    echo_window_seconds: float = 1.5
    """How far back the loudest echo is remembered."""
    learn_seconds: float = 0.25
    """At the start of robot speech, frames only teach the gate how loud the echo is."""


class BargeIn:
    """Listens while the robot speaks; says when the user talks over it."""

    def __init__(self, classifier: FrameClassifier, settings: BargeInSettings | None = None) -> None:
        self.classifier = classifier
        self.settings = settings or BargeInSettings()
        frame_seconds = classifier.frame_samples / SAMPLE_RATE
        self.frame_seconds = frame_seconds
        self._min_frames = max(1, round(self.settings.min_speech_seconds / frame_seconds))
        self._learn_frames = round(self.settings.learn_seconds / frame_seconds)
        self._echo: deque[float] = deque(
            maxlen=max(1, round(self.settings.echo_window_seconds / frame_seconds))
        )
        self._kept: deque[AudioChunk] = deque()
        self._pending = np.zeros(0, np.float32)
        self._pending_start = 0.0
        self._frames = 0
        self._run = 0
        self._hold_frames = max(1, round(LEARN_HOLD_SECONDS / frame_seconds))
        self._rise_per_frame = ECHO_RISE_DB_PER_SECOND * frame_seconds
        self._quiet_frames = self._hold_frames + 1
        self._loud_start = 0.0
        self.onset: float | None = None
        """Stream seconds where the speech that barged in began (once :meth:`feed` said so)."""

    def start(self) -> None:
        """The robot started speaking: forget the last stretch and learn its echo anew."""
        self.classifier.reset()
        self._echo.clear()
        self._kept.clear()
        self._pending = np.zeros(0, np.float32)
        self._frames = self._run = 0
        self._quiet_frames = self._hold_frames + 1
        self.onset = None

    @property
    def echo_db(self) -> float:
        """The loudest recent echo: what the user has to beat by ``margin_db``."""
        return max(self._echo, default=SILENCE_DB)

    def feed(self, chunk: AudioChunk) -> bool:
        """Look at one chunk heard while the robot speaks; True when the user barged in."""
        self._keep(chunk)
        if self._pending.size == 0:
            self._pending_start = chunk.start
        self._pending = np.concatenate([self._pending, chunk.samples])
        size = self.classifier.frame_samples
        while self._pending.size >= size:
            frame, self._pending = self._pending[:size], self._pending[size:]
            start, self._pending_start = self._pending_start, self._pending_start + self.frame_seconds
            if self._step(frame, start):
                return True
        return False

    def take(self) -> list[AudioChunk]:
        """The audio kept so far (up to a second before the barge-in), to hand to the segmenter."""
        kept = list(self._kept)
        self._kept.clear()
        return kept

    def _step(self, frame: Samples, start: float) -> bool:
        level = level_db(frame)
        speech = self.classifier.is_speech(frame)
        self._frames += 1
        if self._frames <= self._learn_frames:
            self._echo.append(level)
            return False
        if level >= self.echo_db + self.settings.margin_db:
            if (
                self._quiet_frames > self._hold_frames
            ):  # after a quiet spell: where the user began, if they did
                self._loud_start = start
            self._quiet_frames = 0
            if not speech:  # the VAD lags at the onset of speech: wait for it, but do not learn this
                return False
            if self._run == 0:
                self.onset = self._loud_start
            self._run += 1
            return self._run >= self._min_frames
        self._run = 0
        self._quiet_frames += 1
        # The robot's own voice (or the room) raises the bar, but not the user's first or quiet
        # syllables: a frame is learnt only well after the last loud one.
        if self._quiet_frames > self._hold_frames:
            # Learnt slowly upward: the user's first syllables rise in a few frames, each below
            # the bar, and would lift it step by step above their voice; the robot's echo rises
            # as fast but its loudest lasts, so the bar still gets there within its window.
            self._echo.append(min(level, self.echo_db + self._rise_per_frame))
        return False

    def _keep(self, chunk: AudioChunk) -> None:
        self._kept.append(chunk)
        while self._kept and chunk.start - self._kept[0].start > KEEP_SECONDS:
            self._kept.popleft()
