"""The world's own words, to bias speech recognition toward them ("turtle not" → "turtlebot").

A general-purpose recognizer does not know that this house has a *turtlebot* and a *dog*, nor that
"undock" is a command: it hears the likeliest English instead. :class:`Bias` nudges Moonshine's
greedy decoder toward words of this world, token by token: among the few tokens the model already
finds likely, one that spells (a beginning of) a known word gets ``bonus`` added to its logit. A
word the model does not consider at all is never forced in, so ordinary speech is left alone.

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
BONUS = 4.0
"""Added to the logit of a token that spells a known word (Moonshine's logits; tuned on the
public sentences: 2 fixed too little, 6 began to replace right words)."""
TOP_K = 8
"""Only the model's own likeliest tokens are candidates for the bonus."""
MIN_LETTERS = 3
"""Shorter beginnings ("t", "do") are too common to mean a word of this world."""


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

    def __init__(self, phrases: Iterable[str], bonus: float = BONUS) -> None:
        self.bonus = bonus
        words = {word for phrase in (*phrases, COMMAND_WORDS) for word in normalize(phrase).split()}
        self.words = frozenset(word for word in words if len(word) >= MIN_LETTERS)
        self._prefixes = frozenset(
            word[:end] for word in self.words for end in range(MIN_LETTERS, len(word) + 1)
        )

    def choose(self, logits: NDArray[np.float32], word: str, pieces: list[str]) -> int:
        """The next token: the argmax of ``logits`` after the bonus.

        ``word`` is the word being spelled so far (lower case, no marker); ``pieces`` maps each
        token id to its text, lower case, with a leading space where the token starts a word.
        """
        top = np.argpartition(logits, -TOP_K)[-TOP_K:]
        best, score = int(np.argmax(logits)), float(logits.max())
        for candidate in (int(c) for c in top):
            piece = pieces[candidate]
            spelled = piece.strip() if piece.startswith(" ") else word + piece
            if spelled in self._prefixes and float(logits[candidate]) + self.bonus > score:
                best, score = candidate, float(logits[candidate]) + self.bonus
        return best
