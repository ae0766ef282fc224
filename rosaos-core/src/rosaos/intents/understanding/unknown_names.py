"""A device name the world does not have: refuse it naming what exists, or ask which one.

"Turn on the garage light" matches a template except for its device: with no garage light, the
engine says which lights there are rather than "not understood", and never acts on a guess.
"Turn on the light" with several lights matches partly several names: it asks which one.
Only when the unknown name shares a word with the names of devices that could do it: "set the
volume to 70" read as a light called "volume" stays "not understood".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from hassil import Intents
from hassil.intents import SlotList
from hassil.recognize import MISSING_ENTITY, RecognizeResult

from rosaos.intents.grammar.phrases import phrase
from rosaos.intents.grammar.vocabulary import strip_article
from rosaos.intents.understanding.readings import Reading, ReadingContext

MIN_LITERAL_FOR_UNKNOWN = 6
"""Template characters an "unknown device" reading must match, so "tell the drone to take off"
is "not understood" rather than "I don't know a device called 'tell the drone'"."""
MAX_UNKNOWN_WORDS = 3
MIN_KIND_WORD = 3
"""Shortest word that counts when comparing an unknown name with known ones ("light", not "a")."""
UNKNOWN_SLOTS = frozenset({"name", "device"})


@dataclass(frozen=True)
class Grammar:
    """One set of templates the matcher recognises against: a driver's, or Home Assistant's."""

    intents: Intents
    lists: dict[str, SlotList]
    ha: bool
    devices: list[str] | None
    """The driver's instances; None for Home Assistant's (the match's domain says who can)."""


class Recognize(Protocol):
    """The matcher's hassil recognition (:meth:`IntentMatcher._recognize`)."""

    def __call__(
        self,
        clause: str,
        intents: Intents,
        lists: dict[str, SlotList],
        ha: bool = False,
        unmatched: bool = False,
    ) -> list[RecognizeResult]: ...


class UnknownNames:
    """Readings for clauses that name a device the world does not have. Cached per clause."""

    def __init__(self, context: ReadingContext, grammars: list[Grammar], recognize: Recognize) -> None:
        self.context = context
        self.language = context.language
        self._grammars = grammars
        self._recognize = recognize
        self._cache: dict[str, Reading | None] = {}
        with_intents = {
            name for grammar in grammars if grammar.devices is not None for name in grammar.devices
        } | set(context.mappings)
        self._kind_words = {
            word
            for device in with_intents
            for name in context.devices[device].spoken_names(self.language)
            for word in name.split()
            if len(word) >= MIN_KIND_WORD
        }

    def clear_cache(self) -> None:
        """Forget cached readings (benchmarks time full recognitions)."""
        self._cache.clear()

    def reading(self, clause: str) -> Reading | None:
        """A refusal naming what exists, or "which one?", when ``clause`` matches except for the
        device's name; None when it is not that (then the clause is "not understood")."""
        if clause in self._cache:
            return self._cache[clause]
        self._cache[clause] = None
        # Cheap test first: an unknown name must share a word with the name of a device that has
        # intents, so a clause sharing none ("play some jazz") cannot give such a reading.
        if not self._kind_words & set(clause.lower().split()):
            return None
        best: tuple[tuple[int, int], Reading] | None = None
        for grammar in self._grammars:
            if grammar.ha and best is not None:
                break  # a driver's reading already outranks any HA one
            for result in self._recognize(
                clause, grammar.intents, grammar.lists, ha=grammar.ha, unmatched=True
            ):
                missing = [
                    e for e in result.unmatched_entities_list if getattr(e, "text", "") != MISSING_ENTITY
                ]
                if len(missing) != 1 or missing[0].name not in UNKNOWN_SLOTS:
                    continue
                if result.text_chunks_matched < MIN_LITERAL_FOR_UNKNOWN:
                    continue
                spoken = strip_article(getattr(missing[0], "text", ""), self.language)
                owners = grammar.devices if grammar.devices is not None else self._capable(result)
                if len(spoken.split()) > MAX_UNKNOWN_WORDS or not self._same_kind(spoken, owners):
                    continue
                # A driver's {device} slot holds exactly the device phrase ("garage light"); an
                # HA name slot may hold only part of it ("garage" + the template's "light").
                key = (int(not grammar.ha), result.text_chunks_matched)
                if best is None or key > best[0]:
                    best = (key, self._not_found(clause, spoken, owners, result.text_chunks_matched))
        self._cache[clause] = best[1] if best is not None else None
        return self._cache[clause]

    def _capable(self, result: RecognizeResult) -> list[str]:
        domain = result.entities["domain"].value if "domain" in result.entities else None
        return self.context.capable(result.intent.name, str(domain) if domain else None)

    def _not_found(self, clause: str, spoken: str, owners: list[str], literal: int) -> Reading:
        """ "the light" is part of several names: ask which one; "the garage light" is none: refuse."""
        partial = [device for device in owners if self._named_partly(spoken, device)]
        if partial:
            return self.context.clarify(clause, literal, 0, partial)
        reply = phrase(self.language, "unknown", phrase=spoken, options=self.context.display(owners))
        return Reading(clause, 0, literal, issue=reply)

    def _named_partly(self, spoken: str, device: str) -> bool:
        """Whether every word of ``spoken`` is in one of ``device``'s names ("light", "bedside")."""
        words = set(spoken.split())
        return any(
            words <= set(name.split()) for name in self.context.devices[device].spoken_names(self.language)
        )

    def _same_kind(self, spoken: str, devices: list[str]) -> bool:
        """Whether ``spoken`` shares a word with a name of one of ``devices``."""
        words = {word for word in spoken.split() if len(word) >= MIN_KIND_WORD}
        return any(
            words & set(name.split())
            for device in devices
            for name in self.context.devices[device].spoken_names(self.language)
        )
