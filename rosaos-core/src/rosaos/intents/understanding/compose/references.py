"""Which devices a phrase means: names, kinds, places and description words, singular or plural.

Every device is known by *nouns* (its kind: "light", "lamp", "robot", "dog", "speaker"; its own
one-word names: "turtlebot") and by *words* (everything its name, aliases, area and description
say: "kitchen", "bedside", "stairwell", "table"). A phrase names the devices that have all its
nouns and most of its other words: "the light over the stairs" is the light whose description
says stairwell, "the bedroom lights" the light in the bedroom, "the robot" the only robot.
Plurals and group words ("the lamps", "both lamps", "every light", "everything") mean all that
fit, and "except …" takes some away. A word before the noun that no device has ("the garage
light") means a device this world does not have: the reader then leaves the sentence to the
engine's refusal. Words are compared loosely (plural -s, and one word a prefix of the other, of
four letters or more: "stairs" ~ "stairwell", "hall" ~ "hallway").
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from dataclasses import dataclass

from rosaos.intents.grammar.capabilities import Capabilities
from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.compose.places import PLACE_NOUNS, name_places

_FUNCTION_WORDS = frozenset(
    [
        "the",
        "a",
        "an",
        "my",
        "our",
        "your",
        "this",
        "that",
        "these",
        "those",
        "its",
        "it",
        "their",
        "his",
        "her",
        "of",
        "in",
        "on",
        "at",
        "by",
        "to",
        "for",
        "with",
        "over",
        "above",
        "under",
        "below",
        "near",
        "next",
        "beside",
        "from",
        "up",
        "down",
        "some",
        "any",
        "please",
        "me",
        "us",
        "you",
        "i",
        "and",
        "is",
        "are",
        "be",
        "so",
        "very",
        "too",
        "there",
        "here",
        "one",
        "ones",
        "thing",
        "things",
        "them",
        "which",
        "who",
        "can",
        "could",
        "would",
        "will",
        "want",
        "need",
        "get",
        "have",
        "make",
        "let",
        "tell",
        "ask",
        "send",
        "bring",
        "take",
        "set",
        "put",
        "turn",
        "switch",
        "go",
        "just",
        "now",
        "also",
        "again",
        "into",
        "onto",
        "out",
        "off",
        "little",
        "bit",
        "way",
        "much",
        "lot",
        "lots",
        "more",
        "less",
        "than",
        "as",
        *PLACE_NOUNS,  # every room is a room: only the word before it says which
    ]
)
_DETERMINERS = frozenset(
    {"the", "my", "our", "your", "this", "that", "these", "those", "its", "their", "a", "an"}
)
_GROUP = frozenset({"all", "every", "each", "both", "everything", "everywhere", "whole", "entire"})
_PRONOUNS = frozenset({"it", "them", "that", "this", "those", "these", "one", "him", "her"})
_EXCEPT = re.compile(
    r"\b(?:except(?:\s+for)?|but(?:\s+not)?|other than|apart from|besides|save for|excluding|not)\b"
)
_GLUE = frozenset(
    {"the", "a", "an", "my", "our", "your", "this", "that", "these", "those", "its", "their", "his", "her",
     "of", "in", "on", "over", "above", "under", "below", "near", "next", "beside", "by", "with", "and",
     *PLACE_NOUNS}
)  # fmt: skip
"""Words inside a device phrase that name nothing themselves ("the light over the stairs")."""
_WORD = re.compile(r"[a-z][a-z0-9'-]*")
_SYNONYMS: tuple[frozenset[str], ...] = tuple(
    frozenset(group.split())
    for group in (
        "sofa couch settee", "tv television telly", "lounge living",
        "hall hallway corridor foyer entryway", "stairs stair stairwell staircase stairway",
        "office study", "bathroom washroom restroom loo", "ceiling overhead", "porch veranda",
        "garden yard backyard", "nursery kid kids children child playroom", "workbench bench", "dining diner", "den lounge",
        "entrance entry doorway", "speaker stereo", "dog puppy doggy doggo pup",
        "bedside nightstand night-stand",
    )
)  # fmt: skip
"""Words people use for the same thing ("the lamp by the couch" for a lamp next to the sofa)."""
_KIN = {"lamp": "light", "bulb": "light", "lantern": "light"}
"""Nouns for the same kind of device, used only when a place or description word says which one."""
MIN_PREFIX = 4
_TAILS = ("side", "stand", "top", "well", "case", "way", "post", "board", "shelf", "light", "lamp")
"""Second halves of compound words: "bed" is said for the bedside, "desk" for the desktop, "night"
for the nightstand ("bedroom" is not one: a bed is in the bedroom, but "by the bed" is not every
light there). A second half of five letters or more is said for the whole too ("chair" for the
armchair)."""
_REMEMBERED_WORDS = 4096


@dataclass(frozen=True)
class Reference:
    """What a phrase says about its devices."""

    devices: tuple[str, ...] = ()
    """The devices it names, before asking which of them can do the action."""
    plural: bool = False
    """A plural or group word: every device that fits, not "which one?"."""
    named: bool = False
    """The phrase names something (a noun or a device's word); False: no device said at all."""
    unknown: bool = False
    """It names a device this world does not have ("the garage light")."""
    pronoun: bool = False
    """Only "it", "them": the device of the clause before."""
    both: bool = False


def singular(word: str) -> str:
    """``lights`` → ``light``, ``batteries`` → ``battery``; short words stay."""
    if len(word) > 4 and word.endswith("ies"):
        return word[:-3] + "y"
    if len(word) > 3 and word.endswith("s") and not word.endswith("ss"):
        return word[:-1]
    return word


def alike(said: str, known: str) -> bool:
    """Whether ``said`` and ``known`` are the same word, loosely (see the module docstring)."""
    said, known = singular(said), singular(known)
    if said == known:
        return True
    short = min(len(said), len(known))
    return short >= MIN_PREFIX and (said.startswith(known) or known.startswith(said))


@dataclass(frozen=True)
class _Known:
    name: str
    nouns: frozenset[str]
    words: frozenset[str]


class References:
    """Resolves phrases against one world's devices."""

    def __init__(
        self, devices: Iterable[DeviceVocabulary], capabilities: dict[str, Capabilities], language: str
    ) -> None:
        self._known: list[_Known] = []
        for device in devices:
            names = device.spoken_names(language)
            nouns = {singular(name.split()[-1]) for name in names}
            declared = capabilities.get(device.name)
            nouns |= set(declared.kind) if declared else set()
            text = " ".join([*names, *device.aliases, device.description, *device.areas(language)])
            text = name_places(text)  # "the sitting room" in a description is the living room
            words = {singular(word) for word in _WORD.findall(text.lower())} - _FUNCTION_WORDS
            words |= {other for group in _SYNONYMS if words & group for other in group}
            self._known.append(_Known(device.name, frozenset(nouns), frozenset(words | nouns)))
        self._nouns = frozenset(noun for known in self._known for noun in known.nouns)
        # Word → devices, so a lookup costs the word's length, not the number of devices (issue 27:
        # the readers run on every event). ``_exact`` holds each known word, ``_prefixes`` every
        # prefix of MIN_PREFIX letters or more: together they answer :func:`alike` for all devices.
        self._exact: dict[str, set[str]] = {}
        self._prefixes: dict[str, set[str]] = {}
        for known in self._known:
            for own in map(singular, known.words):
                self._exact.setdefault(own, set()).add(known.name)
                for end in range(MIN_PREFIX, len(own) + 1):
                    self._prefixes.setdefault(own[:end], set()).add(known.name)
        self._compounds: dict[str, set[str]] = {}
        for known in self._known:
            for own in known.words:
                for tail in _TAILS:
                    if own.endswith(tail) and len(own) - len(tail) >= 3:
                        self._compounds.setdefault(own[: -len(tail)].rstrip("-"), set()).add(known.name)
                for start in range(3, len(own) - 4):  # "chair" for the armchair: its second half
                    self._compounds.setdefault(own[start:], set()).add(known.name)
        self._said: dict[str, frozenset[str]] = {}

    def resolve(self, phrase: str) -> Reference:
        """The devices ``phrase`` names (see :class:`Reference`)."""
        phrase = name_places(phrase)
        tokens = _WORD.findall(phrase)
        group = any(token in _GROUP for token in tokens)
        excepted = _EXCEPT.search(phrase.lower()) if group or self._has_plural(tokens) else None
        if excepted is not None:
            kept = self.resolve(phrase.lower()[: excepted.start()])
            removed = self.resolve(phrase.lower()[excepted.end() :])
            if kept.unknown or removed.unknown or not removed.devices:
                return Reference(unknown=True, named=True)
            rest = tuple(device for device in kept.devices if device not in removed.devices)
            return Reference(rest, plural=True, named=True)
        return self._resolve(tokens, group)

    def names_a_kind(self, phrase: str) -> bool:
        """Whether ``phrase`` says a noun some device is called by ("light", "robot")."""
        return any(singular(token) in self._nouns for token in _WORD.findall(phrase.lower()))

    def kinds(self, device: str) -> frozenset[str]:
        """The nouns ``device`` is called by ("light", "lamp"), for "the one in the kitchen"."""
        return next((known.nouns for known in self._known if known.name == device), frozenset())

    def take(self, tokens: list[str]) -> tuple[tuple[str, ...], list[str]]:
        """The devices ``tokens`` name, and the tokens that are not part of naming them.

        For readers that find a device phrase among other words (a stop: "okay dog, halt"; a
        question: "is the light over the stairs on"). A phrase needs a noun or a device's own
        name ("the kitchen" alone is a place, not a device); one that names a device this world
        lacks names none, and all its words are left over."""
        tokens = _WORD.findall(name_places(" ".join(tokens)))
        naming = [token for token in tokens if self._naming(token)]
        rest = [token for token in tokens if not self._naming(token) and token not in _GLUE]
        if not any(singular(token) in self._nouns for token in naming):
            return (), [token for token in tokens if token not in _GLUE]
        reference = self.resolve(" ".join(token for token in tokens if token not in rest))
        if reference.unknown or not reference.devices:
            return (), [token for token in tokens if token not in _GLUE]
        return reference.devices, rest

    def _naming(self, token: str) -> bool:
        return singular(token) in self._nouns or token in _GROUP or self._known_word(token)

    def _has_plural(self, tokens: list[str]) -> bool:
        return any(singular(token) in self._nouns and singular(token) != token for token in tokens)

    def _resolve(self, tokens: list[str], group: bool) -> Reference:
        heads = [index for index, token in enumerate(tokens) if singular(token) in self._nouns]
        plural = group or any(singular(tokens[index]) != tokens[index] for index in heads)
        both = "both" in tokens
        head_nouns = {singular(tokens[index]) for index in heads}
        others = [
            (index, token)
            for index, token in enumerate(tokens)
            if index not in heads
            and token not in _FUNCTION_WORDS
            and token not in _GROUP
            and not token[0].isdigit()
        ]
        modifiers = [token for _, token in others if self._known_word(token)]
        if (heads and self._unknown_before(tokens, heads, others)) or self._unknown_place(tokens):
            return Reference(unknown=True, named=True)
        if not heads and not modifiers:
            if self._unknown_object(tokens):
                return Reference(unknown=True, named=True)
            everything = "everything" in tokens or ("all" in tokens and len(tokens) <= 2)
            if everything:
                return Reference(tuple(known.name for known in self._known), plural=True, named=True)
            pronoun = any(token in _PRONOUNS for token in tokens)
            return Reference(pronoun=pronoun)
        candidates = [known for known in self._known if head_nouns <= known.nouns]
        if not candidates:
            return Reference(unknown=True, named=True)
        if modifiers:
            scores = {
                known.name: sum(self._has_word(known, word) for word in modifiers) for known in candidates
            }
            best = max(scores.values())
            if best == 0 and heads:
                # "the bedroom lamp" for the bedside light: a lamp is a light, and the place says which
                kin = {_KIN.get(noun, noun) for noun in head_nouns}
                candidates = [known for known in self._known if kin <= {_KIN.get(n, n) for n in known.nouns}]
                scores = {
                    known.name: sum(self._has_word(known, word) for word in modifiers) for known in candidates
                }
                best = max(scores.values(), default=0)
            if best == 0:
                return Reference(unknown=True, named=True)
            candidates = [known for known in candidates if scores[known.name] == best]
            # A place or description word said of a plural noun ("the bedroom lights") still
            # means every device it fits; without a noun, a place means what is there.
            plural = plural or (not heads and "one" not in tokens)  # "the one by the bed": one
        return Reference(tuple(known.name for known in candidates), plural=plural, named=True, both=both)

    def _unknown_before(self, tokens: list[str], heads: list[int], others: list[tuple[int, str]]) -> bool:
        """A word right before a noun that no device has: a device this world lacks."""
        unknown = {index for index, token in others if not self._known_word(token)}
        for head in heads:
            index = head - 1
            while (
                index >= 0
                and (index in heads or index not in unknown)
                and tokens[index] not in _FUNCTION_WORDS
            ):
                index -= 1
            if index >= 0 and index in unknown:
                return True
        return False

    def _unknown_place(self, tokens: list[str]) -> bool:
        """A room this world lacks ("the games room"): its word before "room" names no device, so
        no device is guessed from "room" alone (every room is one)."""
        return any(
            token in PLACE_NOUNS
            and index > 0
            and tokens[index - 1] not in _FUNCTION_WORDS
            and not tokens[index - 1][0].isdigit()
            and not self._known_word(tokens[index - 1])
            for index, token in enumerate(tokens)
        )

    def _unknown_object(self, tokens: list[str]) -> bool:
        """A thing the sentence names that no device is ("turn on the tv", "open the blinds")."""
        for before, token in zip(["", *tokens], tokens, strict=False):
            said_as_object = (before in _DETERMINERS or not before) and token not in _FUNCTION_WORDS
            if (
                said_as_object
                and token not in _GROUP
                and not token[0].isdigit()
                and not self._known_word(token)
            ):
                return True
        return False

    def _known_word(self, token: str) -> bool:
        return bool(self._devices_with(token))

    def _has_word(self, known: _Known, word: str) -> bool:
        return known.name in self._devices_with(word)

    def _devices_with(self, word: str) -> frozenset[str]:
        """The devices with a word :func:`alike` ``word``, from the indexes (remembered per word)."""
        found = self._said.get(word)
        if found is None:
            said = singular(word)
            names = (
                set(self._exact.get(said, ()))
                | self._compounds.get(word, set())
                | self._compounds.get(said, set())
            )
            if len(said) >= MIN_PREFIX:
                names |= self._prefixes.get(said, set())  # a known word that starts with it
                for end in range(MIN_PREFIX, len(said)):  # a known word it starts with
                    names |= self._exact.get(said[:end], set())
            if len(self._said) >= _REMEMBERED_WORDS:
                self._said.clear()  # bounded: what people type is not
            found = self._said[word] = frozenset(names)
        return found
