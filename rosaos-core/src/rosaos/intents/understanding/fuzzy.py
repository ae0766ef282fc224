"""Fuzzy matching: the closest template for a sentence no template spells out exactly.

Learnt from Home Assistant's fuzzy matching (hassil templates as training material, slot values
found first, common words ignored), built here as a small bag-of-words model:

- **Training**, in the constructor: every driver template is expanded (hassil's sampler) into
  skeleton sentences whose slots stay placeholders ("make {device} {bit} brighter"). Each word
  gets an IDF weight over the intents, so "brighter" counts and "the" hardly does.
- **Tagging**: the sentence's device names, areas, list values ("a bit", "blue") and numbers are
  replaced by their placeholders.
- **Scoring**: the weighted F1 overlap of the tagged sentence's words with each skeleton whose
  slots it can fill. Words no template uses weigh the most, so "open the blinds" stays far from
  everything.
- **Checking**: the best skeleton, filled with the user's own values, must be an exact command
  for the engine (so ranges and devices are checked as always). Only that one is considered; a
  weaker skeleton is never tried in its place.

The caller acts on a :class:`FuzzyGuess` at or above :data:`ACT_SCORE`, asks "Did you mean …?"
between :data:`ASK_SCORE` and it, and says "not understood" below.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from hassil import Intents
from hassil.intents import RangeSlotList, TextSlotList, WildcardSlotList
from hassil.sample import sample_expression

ACT_SCORE = 0.85
"""At or above: close enough to act on."""
ASK_SCORE = 0.55
"""At or above (and below :data:`ACT_SCORE`): ask "Did you mean …?" and do nothing yet."""
MAX_SAMPLES = 200
"""Skeletons sampled per template; the first ones cover every word the template uses."""
STOP_WEIGHT = 0.15
SLOT_WEIGHT = 2.0
NUMBER = "{#}"
_PLACEHOLDER = re.compile(r"\{(\w+)\}")
_WORD = re.compile(r"\{\w+\}|\d+(?:[.,]\d+)?|[\w']+|%")
STOP_WORDS: dict[str, frozenset[str]] = {
    "en": frozenset(
        [
            "the",
            "a",
            "an",
            "my",
            "our",
            "your",
            "to",
            "of",
            "in",
            "at",
            "for",
            "please",
            "it",
            "is",
            "its",
            "it's",
            "be",
            "by",
            "me",
            "us",
            "some",
        ]
    ),
}
NUMBER_WORDS = frozenset(
    [
        "zero",
        "one",
        "two",
        "three",
        "four",
        "five",
        "six",
        "seven",
        "eight",
        "nine",
        "ten",
        "eleven",
        "twelve",
        "fifteen",
        "twenty",
        "thirty",
        "forty",
        "fifty",
        "sixty",
        "seventy",
        "eighty",
        "ninety",
        "hundred",
        "half",
    ]
)


@dataclass(frozen=True)
class FuzzyGuess:
    """The closest template for a sentence, filled with the sentence's values."""

    sentence: str
    """An exact command the user may have meant ("make the lamp a bit brighter")."""
    score: float


@dataclass(frozen=True)
class _Skeleton:
    driver: int
    words: tuple[str, ...]
    """Tokens in order; slots as ``{name}`` (ranges as ``{#}``, their list in ``ranges``)."""
    ranges: tuple[str, ...]


class FuzzyMatcher:
    """A bag-of-words model over the templates of a world's drivers, built once."""

    def __init__(
        self,
        drivers: Iterable[tuple[Intents, frozenset[str]]],
        names: Mapping[str, Iterable[str]],
        areas: Iterable[str],
        language: str,
    ) -> None:
        """``drivers``: each driver's hassil intents and the spoken names of its instances;
        ``names``: every spoken name and its devices; ``areas``: every area's name."""
        self.language = language
        self._stop = STOP_WORDS.get(language.split("-")[0], frozenset())
        self._skeletons: list[_Skeleton] = []
        self._driver_names: list[frozenset[str]] = []
        self._values: dict[str, str] = {}
        """Spoken list value → its placeholder (``a bit`` → ``{bit}``)."""
        intent_words: list[set[str]] = []
        for index, (intents, driver_names) in enumerate(drivers):
            self._driver_names.append(driver_names)
            self._learn_lists(intents)
            for intent in intents.intents.values():
                words: set[str] = set()
                for data in intent.data:
                    for sentence in data.sentences:
                        for skeleton in self._sample(index, intents, sentence.expression):
                            if skeleton is not None:
                                self._skeletons.append(skeleton)
                                words.update(skeleton.words)
                intent_words.append(words)
        for name in names:
            self._values[name.lower()] = "{device}"
        for area in areas:
            self._values.setdefault(area.lower(), "{area}")
        self._names = {name.lower(): frozenset(devices) for name, devices in names.items()}
        count = len(intent_words) or 1
        frequency: dict[str, int] = {}
        for words in intent_words:
            for word in words:
                frequency[word] = frequency.get(word, 0) + 1
        self._unknown_weight = math.log(1 + count)
        self._weights = {
            word: self._weigh(word, math.log(1 + count / seen)) for word, seen in frequency.items()
        }
        self._sets = [frozenset(skeleton.words) for skeleton in self._skeletons]
        self._sizes = [math.fsum(self._weight(word) for word in words) for words in self._sets]
        self._slots = [frozenset(word for word in words if word.startswith("{")) for words in self._sets]
        self._by_word: dict[str, list[int]] = {}
        """Content word → the skeletons that use it: only those can score (a word must be shared)."""
        for index, skeleton_words in enumerate(self._sets):
            for word in skeleton_words:
                if word not in self._stop and not word.startswith("{"):
                    self._by_word.setdefault(word, []).append(index)
        self._widest = max((len(value.split()) for value in self._values), default=1)

    def _weigh(self, word: str, idf: float) -> float:
        if word.startswith("{"):
            return SLOT_WEIGHT
        return STOP_WEIGHT if word in self._stop else idf

    def _weight(self, word: str) -> float:
        return self._weights.get(word, STOP_WEIGHT if word in self._stop else self._unknown_weight)

    def _learn_lists(self, intents: Intents) -> None:
        for name, slot_list in intents.slot_lists.items():
            if not isinstance(slot_list, TextSlotList):
                continue
            for value in slot_list.values:
                for spoken in itertools.islice(
                    sample_expression(value.text_in, {}, intents.expansion_rules), MAX_SAMPLES
                ):
                    spoken = " ".join(spoken.lower().split())
                    if spoken:
                        self._values.setdefault(spoken, f"{{{name}}}")

    def _sample(self, driver: int, intents: Intents, expression: object) -> Iterable[_Skeleton | None]:
        seen: set[tuple[str, ...]] = set()
        samples = sample_expression(
            expression,  # type: ignore[arg-type]
            {},
            intents.expansion_rules,
            expand_lists=False,
            expand_ranges=False,
        )
        for text in itertools.islice(samples, MAX_SAMPLES):
            words, ranges = [], []
            wildcard = False
            for word in _WORD.findall(text.lower()):
                slot = _PLACEHOLDER.fullmatch(word)
                if slot is not None:
                    slot_list = intents.slot_lists.get(slot.group(1))
                    if isinstance(slot_list, WildcardSlotList):
                        wildcard = True
                    elif isinstance(slot_list, RangeSlotList) or word == "{number}":
                        ranges.append(slot.group(1))
                        word = NUMBER
                words.append(word)
            # The model is a bag of words: samples with the same words are one skeleton.
            key = tuple(sorted(words))
            if wildcard or key in seen:  # free text cannot be told from a typo: never guessed
                continue
            seen.add(key)
            yield _Skeleton(driver, tuple(words), tuple(ranges))

    def tag(self, text: str) -> list[tuple[str, str]]:
        """``(token, spoken text)`` pairs: slot values replaced by their placeholders (longest first)."""
        words = _WORD.findall(re.sub(r"[^\w'%.\- ]|(?<!\d)\.|\.(?!\d)", " ", text.lower()))
        tagged: list[tuple[str, str]] = []
        index = 0
        while index < len(words):
            for size in range(min(self._widest, len(words) - index), 0, -1):
                spoken = " ".join(words[index : index + size])
                if spoken in self._values:
                    tagged.append((self._values[spoken], spoken))
                    index += size
                    break
            else:
                word = words[index]
                number = word in NUMBER_WORDS or re.fullmatch(r"-?\d+(?:[.,]\d+)?", word) is not None
                tagged.append((NUMBER, word) if number else (word, word))
                index += 1
        return tagged

    def guess(self, text: str) -> FuzzyGuess | None:
        """The closest skeleton, filled with ``text``'s values, and its score; None if none fits."""
        tagged = self.tag(text)
        tokens = frozenset(token for token, _ in tagged)
        if not tokens:
            return None
        spoken_devices = {spoken for token, spoken in tagged if token == "{device}"}
        # fsum: exact, so the order of a frozenset (Python's per-process hash seed) cannot tip a
        # tie between two skeletons one way in one run and the other way in the next.
        size = math.fsum(self._weight(token) for token in tokens)
        best: tuple[float, int] | None = None
        # A name alone is not a command: a skeleton must share a word of its own with the sentence.
        candidates = sorted({index for token in tokens for index in self._by_word.get(token, ())})
        for index in candidates:
            skeleton, words = self._skeletons[index], self._sets[index]
            if not self._slots[index] <= tokens:
                continue  # a slot the sentence cannot fill
            if spoken_devices and not spoken_devices <= self._driver_names[skeleton.driver]:
                continue  # a name this driver's devices do not answer to
            shared = math.fsum(self._weight(word) for word in words & tokens)
            precision, recall = shared / size, shared / self._sizes[index]
            score = 2 * precision * recall / (precision + recall)
            if best is None or score > best[0]:
                best = (score, index)
        if best is None:
            return None
        sentence = self._fill(self._skeletons[best[1]], tagged)
        return FuzzyGuess(sentence, round(best[0], 3)) if sentence else None

    def _fill(self, skeleton: _Skeleton, tagged: list[tuple[str, str]]) -> str | None:
        """The skeleton's words with each slot replaced by what the user said for it."""
        said: dict[str, list[str]] = {}
        for token, spoken in tagged:
            said.setdefault(token, []).append(spoken)
        words = []
        for word in skeleton.words:
            if word.startswith("{"):
                values = said.get(word)
                if not values:
                    return None
                words.append(values.pop(0))
            else:
                words.append(word)
        return " ".join(words).replace(" %", "%")
