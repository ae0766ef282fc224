"""Wake: which transcripts are commands for the robot, and which are just talk in the room.

The wake phrase ("hello", with aliases) is matched on the start of the transcript, after
normalizing case, punctuation and accents: "Hello. Turn on the kitchen light." wakes the robot
with the command "Turn on the kitchen light.". After a wake or a command, a follow-up window
lets the user go on without the phrase. Sustained eye contact (a face on the robot's camera for N
frames in a row) opens the same window.
"""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Literal, Protocol

import numpy as np
from numpy.typing import NDArray

from rosaos.frontends.voice.sources import VoiceError

WakeMode = Literal["phrase", "eye_contact", "either", "off"]

_WORD = re.compile(r"[^\W_]+(?:'[^\W_]+)*")
_TAG = re.compile(r"\[[^\]]*\]|\([^)]*\)|\*[^*]*\*|<[^>]*>")
"""Non-speech annotations STT engines emit: [BLANK_AUDIO], (music), *coughs*, <noise>."""
FILLERS = frozenset({"uh", "um", "umm", "hmm", "hm", "mm", "mhm", "ah", "oh", "er", "erm", "huh", "eh"})
_LEADING_JUNK = " \t\n,.;:!?-–—…'\""


def normalize(text: str) -> str:
    """Lower case, no accents, words separated by single spaces, no punctuation."""
    folded = unicodedata.normalize("NFKD", text.casefold())
    folded = "".join(c for c in folded if not unicodedata.combining(c))
    return " ".join(_WORD.findall(folded))


def is_noise(transcript: str) -> bool:
    """True for transcripts that are not worth sending: empty, annotations only, or only fillers."""
    words = normalize(_TAG.sub(" ", transcript)).split()
    return not words or all(word in FILLERS for word in words)


def strip_wake_phrase(transcript: str, phrases: Iterable[str]) -> str | None:
    """The rest of ``transcript`` after a wake phrase at its start, or None when it has none.

    The rest keeps its own case and punctuation, minus what separated it from the phrase.
    """
    tokens = [(normalize(m.group()), m.end()) for m in _WORD.finditer(transcript)]
    words = [word for word, _ in tokens]
    # Longest phrase first, so "hello there" wins over "hello".
    for phrase in sorted({normalize(p) for p in phrases if normalize(p)}, key=len, reverse=True):
        wanted = phrase.split()
        # "hello" may be tokenized as one word or split ("hel lo" never; "hey, rosa" yes): compare words.
        if words[: len(wanted)] == wanted:
            cut = tokens[len(wanted) - 1][1]
            return transcript[cut:].lstrip(_LEADING_JUNK).strip()
    return None


@dataclass(frozen=True)
class WakeDecision:
    """What to do with one transcript."""

    action: Literal["command", "woke", "ignored"]
    """``command``: send ``command`` to the kernel. ``woke``: only the wake phrase was said.
    ``ignored``: not for the robot (no wake phrase, outside the follow-up window)."""
    command: str = ""
    reason: str = ""
    woke: bool = False
    """This transcript woke the robot (it was asleep before): turn toward the speaker, wave."""


class WakeGate:
    """Decides, transcript by transcript, what the robot was asked. Times are stream seconds."""

    def __init__(
        self,
        mode: WakeMode = "phrase",
        phrase: str = "hello",
        aliases: Sequence[str] = (),
        follow_up_seconds: float = 8.0,
    ) -> None:
        self.mode = mode
        self.phrases = [phrase, *aliases]
        self.follow_up_seconds = follow_up_seconds
        self.awake_until = float("-inf")

    def awake(self, at: float) -> bool:
        """Within the follow-up window at stream time ``at``."""
        return self.mode == "off" or at <= self.awake_until

    def open(self, at: float) -> bool:
        """Open (or extend) the follow-up window from ``at``; True if the robot was asleep."""
        was_awake = self.awake(at)
        self.awake_until = max(self.awake_until, at + self.follow_up_seconds)
        return not was_awake

    def decide(self, transcript: str, start: float, end: float) -> WakeDecision:
        """Decide for a transcript of speech from ``start`` to ``end`` (stream seconds)."""
        if self.mode == "off":
            return WakeDecision("command", transcript.strip(), "no wake needed")
        rest = strip_wake_phrase(transcript, self.phrases) if self.mode != "eye_contact" else None
        if rest is not None:
            woke = self.open(end)
            if not rest or is_noise(rest):
                return WakeDecision("woke", reason=f"wake phrase {self.phrases[0]!r}", woke=woke)
            return WakeDecision("command", rest, f"wake phrase {self.phrases[0]!r}", woke=woke)
        if self.awake(start):
            self.open(end)
            # The phrase may still lead a follow-up ("hello, and the lamp too"): do not send it on.
            command = strip_wake_phrase(transcript, self.phrases)
            return WakeDecision("command", (command or transcript).strip(), "follow-up window")
        wanted = "eye contact" if self.mode == "eye_contact" else f"the wake phrase {self.phrases[0]!r}"
        return WakeDecision("ignored", reason=f"no {wanted}")


class FaceDetector(Protocol):
    """Finds a face in a BGR camera frame."""

    def has_face(self, frame: NDArray[np.uint8]) -> bool: ...


class HaarFaceDetector:
    """OpenCV's bundled frontal-face Haar cascade: offline, fast, and frontal means looking at us."""

    def __init__(self, min_size: int = 40) -> None:
        try:
            import cv2
        except ImportError:
            raise VoiceError(
                "eye-contact wake needs OpenCV: pip install opencv-python-headless (or use wake = 'phrase')"
            ) from None
        self._cv2: Any = cv2  # OpenCV's stubs do not cover cv2.data
        path = f"{self._cv2.data.haarcascades}haarcascade_frontalface_default.xml"
        self._cascade = self._cv2.CascadeClassifier(path)
        if self._cascade.empty():
            raise VoiceError(f"OpenCV could not load its face cascade at {path}; reinstall opencv")
        self.min_size = min_size

    def has_face(self, frame: NDArray[np.uint8]) -> bool:
        gray = frame if frame.ndim == 2 else self._cv2.cvtColor(frame, self._cv2.COLOR_BGR2GRAY)
        faces = self._cascade.detectMultiScale(
            gray, scaleFactor=1.1, minNeighbors=5, minSize=(self.min_size, self.min_size)
        )
        return len(faces) > 0


class EyeContact:
    """Sustained eye contact: a face in ``frames_needed`` consecutive frames."""

    def __init__(self, detector: FaceDetector, frames_needed: int = 5) -> None:
        self.detector = detector
        self.frames_needed = frames_needed
        self.run = 0

    def observe(self, frame: NDArray[np.uint8]) -> bool:
        """Look at one frame; True while the face has been there for ``frames_needed`` frames."""
        self.run = self.run + 1 if self.detector.has_face(frame) else 0
        return self.run >= self.frames_needed
