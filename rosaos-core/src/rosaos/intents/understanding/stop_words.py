"""Recognising "stop" however it is said, and the devices a sentence refers to.

Not a list of sentences: a sentence means stop when it is made of clauses (split at commas,
"and", "then") that each hold only

- a stop word or phrase (:data:`STOP_PHRASES`: stop, halt, freeze, hold it, enough, don't move…),
- words naming devices ("the dog", "the robots", "everything"), resolved from the world's names,
  kinds and plurals (:class:`DeviceRefs`),
- what the device is doing ("walking", "talking") and fillers ("okay", "real quick", "please").

with at least one stop word. Other clauses are kept as the rest of the sentence, run after the
stop ("stop the dog and turn on the light"), unless a bare stop follows a command: "walk forward,
then stop" is how that walk ends. "Okay, enough, halt the dog", "dog, stop", "stop everything" and
"freeze!" are stops; "stop at the kitchen" (a place) and "walk forward then stop" (a command
that ends by itself) are not. A stop word right after a negation ("don't stop the music") is not
a stop. A name several devices share ("the robot") means all of them: a stop is never held back
to ask which one.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.compose.complaints import complaint, idle
from rosaos.intents.understanding.compose.references import References
from rosaos.intents.understanding.compose.speech import asks, remark

STOP_PHRASES = (
    "emergency stop", "stop moving", "stop it", "hold it", "hold on", "hold up", "stand still",
    "stay still", "keep still", "stay put", "don't move", "do not move", "dont move", "that's enough",
    "thats enough", "that is enough", "quit it", "cut it out", "knock it off", "shut it down",
    "stop", "halt", "freeze", "enough", "cease", "abort", "whoa", "woah", "stopp",
)  # fmt: skip
"""Words and phrases that mean stop, longest first where one contains another."""

INTERJECTIONS = frozenset({"whoa", "woah", "hold on", "hold up"})
"""Stop words that are also what people say before a request ("whoa, that's loud, turn it down"):
a stop alone, or beside a remark ("whoa, the dog is too close"), but not before a command."""

DOING = frozenset(
    [
        "moving",
        "walking",
        "driving",
        "rolling",
        "going",
        "running",
        "turning",
        "spinning",
        "rotating",
        "searching",
        "looking",
        "talking",
        "speaking",
        "playing",
        "dancing",
        "now",
        "right",
        "immediately",
        "instantly",
        "at",
        "once",
        "already",
        "again",
        "everything",
        "all",
        "it",
        "that",
        "this",
        "what",
        "whatever",
        "you're",
        "you",
        "are",
        "doing",
        "from",
    ]
)
"""Words that may follow a stop word without changing what it stops."""

EVERYTHING = frozenset({"everything", "all", "everyone", "everybody", "it all", "all of it", "all of you"})

FILLERS = frozenset(
    [
        "okay",
        "ok",
        "oh",
        "man",
        "hey",
        "please",
        "pls",
        "now",
        "just",
        "right",
        "alright",
        "all",
        "so",
        "well",
        "uh",
        "um",
        "er",
        "ah",
        "hmm",
        "wait",
        "no",
        "nope",
        "yo",
        "dude",
        "buddy",
        "jeez",
        "god",
        "damn",
        "dammit",
        "seriously",
        "quick",
        "quickly",
        "real",
        "really",
        "i",
        "said",
        "told",
        "you",
        "could",
        "can",
        "would",
        "will",
        "you",
        "ya",
        "guys",
        "thanks",
        "thank",
        "the",
        "a",
        "my",
        "our",
        "your",
        "both",
        "every",
        "each",
        "make",
        "get",
        "have",
        "tell",
        "ask",
        "let",
        "to",
        "there",
        "easy",
        "wow",
        "oops",
        "whoops",
        "yikes",
        "ouch",
        "careful",
        "gosh",
        "geez",
        "ugh",
        "eh",
    ]
)
"""Words that carry no command: ignored around a stop (also the causative frame: "make the dog
stop", "tell the robot to halt")."""

_NEGATED_MOVES = ("don't move", "do not move", "dont move")
NEGATIONS = ("don't", "dont", "do not", "never", "not", "no need to", "doesn't")
_CLAUSES = re.compile(r"\s*(?:[,;.!?]+|\band then\b|\bthen\b|\band\b)\s*")
_WORD = re.compile(r"[a-z0-9']+|[,;.!?]")
"""Words, and the punctuation that ends a clause."""


@dataclass(frozen=True)
class StopRequest:
    """A sentence that means stop: the devices it names (empty: a bare "stop", everything)."""

    devices: tuple[str, ...]
    rest: str = ""
    """Other commands in the sentence ("stop the dog and turn on the light"): run after the stop."""


class DeviceRefs:
    """The world's devices by the words people call them, for the stop and question readers.

    One resolver for every reader: this is the compositional reader's
    (:class:`~rosaos.intents.understanding.compose.references.References`: names, aliases, kinds,
    places and description words, plurals), so "stop the light over the stairs" and "is the light
    over the stairs on?" mean the device that "turn off the light over the stairs" does."""

    def __init__(self, devices: Sequence[DeviceVocabulary], language: str = "en") -> None:
        self.language = language
        capabilities = {
            device.name: file.capabilities
            for device in devices
            if (file := device.mapping_file()) is not None and file.capabilities is not None
        }
        self._references = References(devices, capabilities, language)

    def resolve(self, text: str) -> tuple[str, ...] | None:
        """The devices ``text`` names (all of a shared kind), or None when it is not only names."""
        found, rest = self.take(_words(text))
        return tuple(found) if found and not [word for word in rest if word not in FILLERS] else None

    def take(self, words: list[str]) -> tuple[list[str], list[str]]:
        """The devices named in ``words`` (in world order), and the words left over."""
        tokens = [word[:-2] if word.endswith("'s") else word for word in words]
        found, rest = self._references.take(tokens)
        return list(found), rest


def read_stop(text: str, refs: DeviceRefs) -> StopRequest | None:
    """What ``text`` asks to stop, or None when it does not mean stop (see the module docstring)."""
    said = " ".join(_words(text))
    if not said or _negated(said) or not _count_stops(said):
        return None  # no stop word: not a stop, and no device lookup on every event that is not
    clauses: list[tuple[str, str, list[str]]] = []  # (kind, clause, devices): stop, name or other
    for clause in filter(None, (piece.strip() for piece in _CLAUSES.split(said))):
        found, rest = refs.take(_strip_stops(clause.split()))
        if found and any(f" {phrase} " in f" {clause} " for phrase in _NEGATED_MOVES):
            return None  # "don't move the dog" refuses a command; "dog, don't move" is a stop
        if [word for word in rest if word not in FILLERS and word not in DOING]:
            clauses.append(("other", clause, found))
        else:
            clauses.append(("stop" if _count_stops(clause) else "name", clause, found))
    if not any(kind == "stop" for kind, _, _ in clauses):
        return None
    if _only_exclaimed(clauses):
        return None  # "whoa, the music is way too loud, turn it down": surprise, then a request
    first = next((index for index, (kind, _, _) in enumerate(clauses) if kind == "other"), len(clauses))
    command = next(
        (index for index, (kind, clause, _) in enumerate(clauses) if _commands(kind, clause)), None
    )
    if command is not None and any(kind == "stop" and not found for kind, _, found in clauses[command:]):
        return None  # "walk forward, then stop": the end of that command, not a stop of its own
    devices = [
        name
        for index, (kind, _, found) in enumerate(clauses)
        if kind == "stop" or (kind == "name" and index < first)
        for name in found
    ]
    rest = [
        clause
        for index, (kind, clause, found) in enumerate(clauses)
        # a reason beside the stop ("…, I need to concentrate") is no command of its own, nor is
        # a remark that says stop itself ("you've gone far enough, stop")
        if (kind == "other" and not ((_why(clause) or _count_stops(clause)) and not found))
        or (kind == "name" and index > first)
    ]
    return StopRequest(tuple(dict.fromkeys(devices)), " and ".join(rest))


def _only_exclaimed(clauses: list[tuple[str, str, list[str]]]) -> bool:
    """Whether every stop in ``clauses`` is an interjection naming nothing, and another clause asks
    for something (a command, not a remark about what happens)."""
    stops = [(clause, found) for kind, clause, found in clauses if kind == "stop"]
    exclaimed = all(
        not found and not _count_stops(" ".join(_strip_interjections(clause.split())))
        for clause, found in stops
    )
    asked = any(
        kind == "other"
        # "whoa, that's way too loud" asks for a step; "whoa, too fast" is a stop with its reason
        and (complaint(clause) is not None or not (remark(clause) or _TOO.match(clause)))
        and not asks(clause)
        and not _count_stops(clause)
        for kind, clause, _ in clauses
    )
    return exclaimed and asked


_TOO = re.compile(
    r"^(?:(?:that's|it's|this is|you're)\s+)?(?:(?:way|far|much|a bit|a little)\s+)?(?:too|so)\s+\w+$"
)


def _commands(kind: str, clause: str) -> bool:
    """Whether ``clause`` may be a command a later bare stop ends ("walk forward, then stop").

    A remark or a reason is not ("okay, that's far enough, stop": the robot stops), nor a clause
    that says stop itself ("you've gone far enough"): a bare stop after those is a stop of its own.
    """
    return kind == "other" and not remark(clause) and not idle(clause) and not _count_stops(clause)


def _why(clause: str) -> bool:
    """A clause beside a stop that only says why: a reason ("I need to concentrate", :func:`idle`)
    or "too fast" (a complaint about no setting this engine changes)."""
    return idle(clause) or (_TOO.match(clause) is not None and complaint(clause) is None)


def _strip_interjections(words: list[str]) -> list[str]:
    text = f" {' '.join(words)} "
    for phrase in sorted(INTERJECTIONS, key=len, reverse=True):
        text = text.replace(f" {phrase} ", " ")
    return text.split()


def _words(text: str) -> list[str]:
    cleaned = text.lower().replace("’", "'")
    return _WORD.findall(cleaned)


def _strip_stops(words: list[str]) -> list[str]:
    """``words`` without its stop phrases and everything-words."""
    text = f" {' '.join(words)} "
    for phrase in (*STOP_PHRASES, *sorted(EVERYTHING, key=len, reverse=True)):
        while f" {phrase} " in text:
            text = text.replace(f" {phrase} ", " ")
    return text.split()


def _count_stops(clause: str) -> int:
    text = f" {clause} "
    return sum(text.count(f" {phrase} ") for phrase in STOP_PHRASES if " " not in phrase) + sum(
        1 for phrase in STOP_PHRASES if " " in phrase and f" {phrase} " in text
    )


def _negated(said: str) -> bool:
    """A negation right before a stop word ("don't stop the music"): not a stop."""
    text = f" {said} "
    for negation in NEGATIONS:
        for phrase in ("stop", "halt", "freeze", "pause"):
            if f" {negation} {phrase} " in text:
                return True
    return False
