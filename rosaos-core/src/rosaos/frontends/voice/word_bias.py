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
SMALL_WORDS = NOT_BIASED | {"a", "an", "at", "by", "in", "is", "it", "me", "my", "of", "on", "to", "up"}
"""Words a mended name never begins or ends with: "to the left" is no "turtlebot"."""
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
        spaced = {normalize(phrase).replace(" ", "") for phrase in phrases if " " in normalize(phrase)}
        self.sounds = {
            sound(phrase): phrase
            for phrase in (*phrases, *self.names)
            if len(sound(phrase)) >= MIN_SOUNDS
            and (
                " " in normalize(phrase) or normalize(phrase) not in spaced
            )  # "livingroomlamp" is a spelling
            and not set(normalize(phrase).split()) <= self.words - self.names
        }
        """How each name, room and title sounds (:func:`sound`), for mending what was misheard as other words."""
        self.known = self.words | self.names | NOT_BIASED
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
            found = [
                (match[0], size, match[1])
                for size in (3, 2, 1)
                if i + size <= len(words)
                and SMALL_WORDS.isdisjoint({normalize(words[i]), normalize(words[i + size - 1])})
                for match in [self._near_name(words[i : i + size])]
                if match is not None
            ]
            if found:
                _, size, name = min(
                    found, key=lambda match: (match[0], -match[1])
                )  # closest; then most words
                last = words[i + size - 1]
                out.append(name + last[len(last.rstrip(".,!?;:")) :])  # keep the punctuation
                i += size
            else:
                out.append(words[i])
                i += 1
        return " ".join(out)

    def _near_name(self, window: list[str]) -> tuple[int, str] | None:
        """The name ``window`` is a near miss of, and how near, if any (not when it already is one).

        By letters first ("turtle moth", "Debusy"), then by sound ("total not", "Clara blue"); a
        sound match must begin with a word that is not this world's ("the dock", "turtlebot 90"
        stay), and hold no number.
        """
        plain = [normalize(word) for word in window]
        letters = "".join(plain).replace(" ", "")
        if letters in self.names or plain[0] in self.names or any(c.isdigit() for c in letters):
            return None  # already a name, or a name and what follows it ("turtlebot 90")
        if len(window) == 1 and plain[0] in self.words:
            return None
        if len(window) == 1 or not any(word in self.words or word in self.names for word in plain[1:]):
            for name in self.names:  # "the dock": words of this world in their own right stay apart
                distance = _edits(letters, name) if abs(len(name) - len(letters)) <= 2 else len(name)
                if distance <= max(1, len(name) // 4):
                    return distance, name
        if plain[0] in self.known or not self.names.isdisjoint(plain):
            return None
        heard = sound(" ".join(plain))
        matches = [
            (_edits(heard, key), phrase)
            for key, phrase in self.sounds.items()
            if abs(len(key) - len(heard)) <= 1 and _edits(heard, key) <= (1 if len(key) < 6 else 2)
        ]
        return min((match for match in matches if self._word_for_word(plain, match[1])), default=None)

    def _word_for_word(self, plain: list[str], phrase: str) -> bool:
        """A phrase of as many words as was heard must sound alike word by word.

        "garage light" is not "kitchen light" (the whole sounds close, "garage" and "kitchen" do not).
        """
        words = normalize(phrase).split()
        if len(words) != len(plain) or len(words) == 1:
            return True
        return all(_edits(sound(a), sound(b)) <= 1 for a, b in zip(plain, words, strict=True))


def sound(text: str) -> str:
    """A rough key of how ``text`` sounds, to match what a recognizer bent into other words.

    Consonants only, with spelling variants and voicing folded together ("turtle not" →
    ``trtlnt``, "turtlebot" → ``trtlpt``; "Clara blue" → ``klrpl``, "Clair de Lune" → ``klrtln``):
    an engine that mishears a name keeps most of its consonants and their order.
    """
    words = []
    for word in normalize(text).split():
        for spelled, said in _SPELLINGS:
            word = word.replace(spelled, said)
        word = word[1:] if word.startswith("kn") else word
        words.append("".join(letter for i, letter in enumerate(word) if i == 0 or word[i - 1] != letter))
    return "".join(words).translate(_FOLD)


_SPELLINGS = (
    ("ph", "f"),
    ("ck", "k"),
    ("gh", ""),
    ("sh", "s"),
    ("ch", "k"),
    ("th", "t"),
    ("qu", "kw"),
    ("x", "ks"),
)
_FOLD = str.maketrans("bdgvzcq", "ptkfskk", "aeiouwyh")
MIN_SOUNDS = 4
"""Shorter keys ("dog": ``tk``) match too many ordinary words to mend toward."""


def _edits(a: str, b: str) -> int:
    """Levenshtein distance."""
    previous = list(range(len(b) + 1))
    for i, x in enumerate(a, 1):
        current = [i]
        for j, y in enumerate(b, 1):
            current.append(min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (x != y)))
        previous = current
    return previous[-1]
