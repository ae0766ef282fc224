"""Everyday ways of saying a command that templates do not spell out, read back to plain commands.

People wrap commands in politeness ("could you please …", "… for me, thanks"), address a robot
by name first or last ("turtlebot, go one meter ahead", "turn your head right, Reachy"), and
speech-to-text splits names ("turtle bot"). This module turns such a sentence into the plainer
sentences it stands for, each with the devices it was addressed to; the matcher tries them in
order and keeps the first exact reading. Nothing here knows a sentence: only word lists per
language and the world's device names.

A command said in the negative ("don't turn on the lamp") is read too, so it can be refused by
name rather than acted on or guessed at.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

# Words around a command that do not change it. Longest first, so "could you please" goes whole.
LEADING_FILLERS: dict[str, tuple[str, ...]] = {
    "en": (
        "could you please",
        "can you please",
        "would you please",
        "will you please",
        "i'd like you to",
        "i would like you to",
        "i want you to",
        "could you",
        "can you",
        "would you",
        "will you",
        "please",
        "hey",
        "okay",
        "ok",
        "so",
        "now",
        "just",
        "oh",
        "and",
    ),
}
TRAILING_FILLERS: dict[str, tuple[str, ...]] = {
    "en": (
        "for me please",
        "please thank you",
        "please thanks",
        "thank you",
        "for me",
        "please",
        "thanks",
        "right now",
        "now",
        "would you",
        "will you",
        "ok",
        "okay",
    ),
}
# A command said in the negative. Only at the start: "I don't like this song" is a request.
NEGATIONS: dict[str, tuple[str, ...]] = {
    "en": ("don't", "do not", "dont", "never", "please don't", "please do not", "no need to"),
}
_EDGE_PUNCTUATION = re.compile(r"^[\s,;:.!?]+|[\s,;:.!?]+$")


@dataclass(frozen=True)
class Rephrasing:
    """A plainer sentence, and the devices the user addressed by name, if any."""

    text: str
    addressed: frozenset[str] | None = None


def _table(table: dict[str, tuple[str, ...]], language: str) -> tuple[str, ...]:
    return table.get(language.split("-")[0], ())


def strip_fillers(text: str, language: str) -> str:
    """``text`` without the politeness words around it ("could you please …, thanks")."""
    text = _EDGE_PUNCTUATION.sub("", text)
    changed = True
    while changed:
        changed = False
        lowered = text.lower()
        for filler in _table(LEADING_FILLERS, language):
            if lowered.startswith(filler + " ") or lowered.startswith(filler + ","):
                text, changed = _EDGE_PUNCTUATION.sub("", text[len(filler) :]), True
                break
        lowered = text.lower()
        for filler in _table(TRAILING_FILLERS, language):
            if lowered.endswith(" " + filler) or lowered.endswith("," + filler):
                text, changed = _EDGE_PUNCTUATION.sub("", text[: -len(filler)]), True
                break
    return text


def negated(text: str, language: str) -> str | None:
    """The command ``text`` says not to do ("don't turn on the lamp" → "turn on the lamp"), or None."""
    plain = strip_fillers(text, language)
    lowered = plain.lower()
    for negation in sorted(_table(NEGATIONS, language), key=len, reverse=True):
        if lowered.startswith(negation + " "):
            return plain[len(negation) + 1 :].strip()
    return None


def join_split_names(text: str, names: Iterable[str]) -> str:
    """``text`` with a one-word name that speech-to-text split put back ("turtle bot" → "turtlebot")."""
    words = text.split()
    single = {name for name in names if " " not in name and len(name) >= 6}
    for size in (3, 2):
        index = 0
        while index + size <= len(words):
            joined = "".join(words[index : index + size]).lower()
            if joined in single:
                words[index : index + size] = [joined]
            index += 1
    return " ".join(words)


def rephrasings(text: str, language: str, named: Iterable[tuple[str, frozenset[str]]]) -> list[Rephrasing]:
    """The plainer sentences ``text`` stands for, most literal first.

    ``named``: every spoken name and the devices answering to it. A sentence that starts or
    ends with a name set off by a comma ("dog, a bit closer please") is a command to that device.
    """
    names = dict(named)
    found: list[Rephrasing] = []
    joined = join_split_names(text, names)
    plain = strip_fillers(joined, language)
    for candidate in (joined, plain):
        if candidate != text:
            found.append(Rephrasing(candidate))
    for part, rest in _vocatives(joined):
        name = strip_fillers(part, language).lower()
        name = re.sub(r"^(?:the|my|our)\s+", "", name)
        if name in names and rest:
            found.append(Rephrasing(strip_fillers(rest, language), names[name]))
    return list(dict.fromkeys(found))


def _vocatives(text: str) -> list[tuple[str, str]]:
    """``(name part, command part)`` for a name said first or last, set off by a comma."""
    pairs = []
    if "," in text:
        head, _, tail = text.partition(",")
        pairs.append((head, tail))
        head, _, tail = text.rpartition(",")
        pairs.append((tail, head))
    return [(_EDGE_PUNCTUATION.sub("", name), _EDGE_PUNCTUATION.sub("", rest)) for name, rest in pairs]
