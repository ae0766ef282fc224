"""The world's own words, to bias speech recognition toward them ("turtle not" → "turtlebot").

A general-purpose recognizer does not know that this house has a *turtlebot* and a *dog*, nor that
"undock" is a command: it hears the likeliest English instead. Two steps bring it back:

- :class:`Bias` nudges Moonshine's greedy decoder toward words of this world, token by token:
  among the few tokens the model already finds likely, one that spells (a beginning of) a known
  word gets ``bonus`` added to its logit. A word the model does not consider at all is never
  forced in, so ordinary speech is left alone.
- :meth:`Bias.correct` then mends what the decoder still split or bent: one to three heard words
  whose letters are within a small edit distance of a device name ("turtle not", "turtle, but")
  become that name.

The words come from the configuration: device names and aliases, rooms, the simulator catalog's
tracks, artists, albums and genres, and :data:`COMMAND_WORDS`, the verbs and nouns of the commands
the offline engine understands.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rosaos.frontends.voice.wake import normalize

COMMAND_WORDS = (
    "turn on off switch set dim brighten brightness toggle light lights lamp percent warm white "
    "red green blue yellow orange purple pink color colour play pause resume stop skip next previous "
    "song track music volume louder quieter up down shuffle repeat undock dock drive forward "
    "backward back left right degrees meter meters walk sit stand look say tell take land fly "
    "timer minutes seconds cancel"
)
"""Words of the commands the offline engine's templates use (issue 25: "the command vocabulary")."""
BONUS = 3.0
"""Added to the logit of a token that spells a known word (Moonshine's logits; tuned on the
public sentences: 2 fixed too little, 6 began to replace right words)."""
TOP_K = 8
"""Only the model's own likeliest tokens are candidates for the bonus."""
MIN_LETTERS = 3
"""Shorter beginnings ("t", "do") are too common to mean a word of this world."""
NOT_BIASED = frozenset({"the", "and", "for", "off", "you", "your", "with", "from", "its", "all", "some"})
"""Common words (from catalog titles, or "off" against "on") a bonus would only put in wrongly."""
MIN_NAME_LETTERS = 6
"""Only names this long are mended from near misses: shorter ones ("dog") have too many neighbours."""


def world_phrases(devices: Mapping[str, Mapping[str, Any]]) -> list[str]:
    """Names, aliases, rooms and catalog entries of devices given as ``[devices.NAME]`` tables."""
    phrases: list[str] = []
    for name, device in devices.items():
        phrases += [name.replace("_", " "), name.replace("_", "")]
        phrases += [str(alias) for alias in device.get("aliases") or ()]
        if device.get("area"):
            phrases.append(str(device["area"]))
        sim = device.get("sim") or {}
        for entry in sim.get("catalog") or () if isinstance(sim, Mapping) else ():
            if isinstance(entry, Mapping):
                phrases += [str(value) for value in entry.values() if isinstance(value, str)]
    return phrases


class Bias:
    """Nudges greedy decoding toward the words of ``phrases`` (and :data:`COMMAND_WORDS`)."""

    def __init__(self, phrases: Iterable[str], bonus: float = BONUS, names: Iterable[str] = ()) -> None:
        self.bonus = bonus
        phrases = list(phrases)
        words = {word for phrase in (*phrases, COMMAND_WORDS) for word in normalize(phrase).split()}
        self.words = frozenset(word for word in words if len(word) >= MIN_LETTERS) - NOT_BIASED
        self.names = frozenset(
            word
            for phrase in (*phrases, *names)
            for word in normalize(phrase).split()
            if len(word) >= MIN_NAME_LETTERS
        )
        """Words :meth:`correct` mends toward: the long words of names, rooms and titles."""
        self._prefixes = frozenset(
            word[:end] for word in self.words for end in range(MIN_LETTERS, len(word) + 1)
        )

    def choose(self, logits: NDArray[np.float32], word: str, pieces: list[str]) -> int:
        """The next token: the argmax of ``logits`` after the bonus.

        ``word`` is the word being spelled so far (lower case, no marker); ``pieces`` maps each
        token id to its text, lower case, with a leading space where the token starts a word.
        """
        k = min(TOP_K, logits.size)
        top = np.argpartition(logits, -k)[-k:]
        best, score = int(np.argmax(logits)), float(logits.max())
        for candidate in (int(c) for c in top):
            piece = pieces[candidate]
            starts = piece.startswith(" ")
            spelled = piece.strip() if starts else word + piece
            # A word begun ("▁for") is too often a common word: only a whole known word, or the
            # continuation of a known word's beginning ("turtle" + "bot"), earns the bonus.
            known = spelled in self.words or (
                not starts and word in self._prefixes and spelled in self._prefixes
            )
            if known and float(logits[candidate]) + self.bonus > score:
                best, score = candidate, float(logits[candidate]) + self.bonus
        return best

    def correct(self, transcript: str) -> str:
        """``transcript`` with near misses of long names mended ("Drive the turtle not forward")."""
        words = transcript.split()
        out: list[str] = []
        i = 0
        while i < len(words):
            for size in (3, 2, 1):
                window = words[i : i + size]
                if len(window) < size:
                    continue
                name = self._near_name(window)
                if name is not None:
                    tail = window[-1][len(window[-1].rstrip(".,!?;:")) :]  # keep the punctuation
                    out.append(name + tail)
                    i += size
                    break
            else:
                out.append(words[i])
                i += 1
        return " ".join(out)

    def _near_name(self, window: list[str]) -> str | None:
        """The name ``window`` is a near miss of, if any (not when it already is one)."""
        plain = [normalize(word) for word in window]
        if len(window) > 1 and any(word in self.words or word in self.names for word in plain[1:]):
            return None  # "the dock": words of this world in their own right stay apart
        letters = "".join(plain).replace(" ", "")
        if letters in self.names or (len(window) == 1 and plain[0] in self.words):
            return None
        best: tuple[int, str] | None = None
        for name in self.names:
            if abs(len(name) - len(letters)) > 2:
                continue
            distance = _edits(letters, name)
            if distance <= max(1, len(name) // 4) and (best is None or distance < best[0]):
                best = (distance, name)
        return best[1] if best else None


def _edits(a: str, b: str) -> int:
    """Levenshtein distance."""
    previous = list(range(len(b) + 1))
    for i, x in enumerate(a, 1):
        current = [i]
        for j, y in enumerate(b, 1):
            current.append(min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (x != y)))
        previous = current
    return previous[-1]
