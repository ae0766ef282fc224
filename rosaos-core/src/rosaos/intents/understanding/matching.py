"""Sentence → plans: the matching half of the local-intent engine, usable on its own.

:meth:`IntentMatcher.match` takes what the user said and returns a :class:`MatchResult`: the
processes to launch (one per device, each with a readable task and a ``rosaos-plan``), or the
question / refusal to reply with, or "not understood". It never guesses: a sentence that could
mean several devices, or names one that does not exist, yields a reply and no process.

Templates come from each driver's ``intents.yaml`` (``{device}`` = that driver's instances) and
from Home Assistant's built-in intents for the configured language (see
:mod:`rosaos.intents.grammar.ha_intents`). All hassil structures are built once, in the constructor.

A sentence with several commands ("turn on the lamp and play some jazz") is split at
conjunctions, but only when the whole sentence does not match by itself, or matched only by a
wildcard swallowing a conjunction ("play {search_query}").

A command may leave its device out, as people do: "undock the turtlebot and drive it forward one
meter" or "... and drive forward one meter" mean the turtlebot of the command before. Such a
clause is read again with that device's name in place of the pronoun, or inserted after its first
words; it is taken only when that reading is exact and about that device alone. A sentence that
leaves its device out from the start ("drive forward one meter") is read the same way against
every device: one that fits is acted on, several get "which one?", exactly as a missing name does.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Sequence
from functools import cache

from hassil import Intents, recognize_all
from hassil.intents import SlotList, TextSlotList
from hassil.recognize import RecognizeResult

from rosaos.intents.grammar.ha_intents import NO_AREA, load_ha_intents
from rosaos.intents.grammar.phrases import confirms, conjunctions
from rosaos.intents.grammar.vocabulary import ARTICLES, DeviceVocabulary
from rosaos.intents.understanding.absent_kinds import AbsentKinds
from rosaos.intents.understanding.compose.complaints import without_idle
from rosaos.intents.understanding.compose.reader import Composer
from rosaos.intents.understanding.compose.speech import normalise, says_stop, wished
from rosaos.intents.understanding.compose.spoken import tidy
from rosaos.intents.understanding.driver_grammars import driver_intents
from rosaos.intents.understanding.fuzzy import FuzzyMatcher
from rosaos.intents.understanding.generalize import understand
from rosaos.intents.understanding.left_out import LeftOutDevices
from rosaos.intents.understanding.match_result import MatchResult, ProcessPlan, build_result, no_match
from rosaos.intents.understanding.ranges import refuse_bad_number
from rosaos.intents.understanding.readings import (
    RANK_ANY,
    Focus,
    Reading,
    ReadingContext,
    driver_reading,
    ha_reading,
)
from rosaos.intents.understanding.unknown_names import Grammar, UnknownNames
from rosaos.intents.understanding.wildcard_checks import gives_reason, says_nothing

__all__ = ["IntentMatcher", "MatchResult", "ProcessPlan"]

MAX_RESULTS_PER_SOURCE = 16
"""hassil can yield many equivalent parses; the first ones are the most literal."""
MAX_PIECES = 6
"""Sentences cut into more pieces than this are not split (each split costs recognitions)."""
CACHE_SIZE = 512


class IntentMatcher(LeftOutDevices):
    """Matches sentences against the intents of one world's devices, in one language."""

    def __init__(self, devices: Sequence[DeviceVocabulary], language: str = "en") -> None:
        self.language = language
        self.devices = {device.name: device for device in devices}
        self.context = ReadingContext(self.devices, language)
        self._drivers = driver_intents(self.devices, self.language)
        mapped = {name for mapping in self.context.mappings.values() for name in mapping.intents}
        domains = {mapping.domain for mapping in self.context.mappings.values()}
        targets = {"name"} | ({"area"} if self.context.areas else set())
        self._ha = load_ha_intents(language, mapped, domains, targets)
        self._skip_words = list(self._ha.skip_words) if self._ha is not None else []
        self._filler = {article.strip() for article in ARTICLES.get(language, ()) + ARTICLES["en"]}
        self._filler |= {word for skip in self._skip_words for word in skip.lower().split()}
        self._ha_lists: dict[str, SlotList] = {
            "name": TextSlotList.from_tuples(
                [
                    (spoken, spoken, {"domain": self.context.mappings[device].domain})
                    for spoken, owners in self.context.names.items()
                    for device in owners
                    if device in self.context.mappings
                ],
                allow_template=False,
            ),
            "area": TextSlotList.from_tuples(
                [(area, area) for area in self.context.areas], allow_template=False
            ),
        }
        words = "|".join(re.escape(word) for word in conjunctions(language))
        # ", and then" is one separator: a comma, a conjunction, or a comma then a conjunction.
        self._splitter = re.compile(rf"\s*((?:,\s*)?\b(?:{words})\b|,)\s*", re.IGNORECASE)
        self._cache: dict[tuple[str, Focus, str | None], Reading | None] = {}
        self._fuzzy = FuzzyMatcher(
            [(driver.intents, frozenset(driver.device_list_names)) for driver in self._drivers],
            self.context.names,
            self.context.areas,
            language,
        )
        grammars = [Grammar(driver.intents, driver.lists, False, driver.devices) for driver in self._drivers]
        if self._ha is not None:
            grammars.append(Grammar(self._ha, self._ha_lists, True, None))
        self._unknown_names = UnknownNames(self.context, grammars, self._recognize)
        self._composer = Composer(self.context, devices, language)
        self._absent_kinds = AbsentKinds(self.context)

    def clear_cache(self) -> None:
        """Forget cached clause readings (benchmarks time full recognitions)."""
        self._cache.clear()
        self._unknown_names.clear_cache()

    def choice(self, text: str) -> frozenset[str]:
        """The devices ``text`` picks when it is only a choice ("the kitchen one", "bedroom light"),
        else nothing: "is the kitchen light on?" names a device too, but is a new command."""
        focus, leftover = self.context.named_in(text)
        return focus if len([word for word in leftover if word not in self._filler]) <= 1 else frozenset()

    def follow_up(self, question: str, answer: str) -> MatchResult | None:
        """``question`` (a sentence that got "which one?") again, limited to the devices ``answer``
        picks, or the command "Did you mean …?" offered when ``answer`` is yes. None when the
        answer is neither, or the question still does not resolve."""
        if confirms(answer, self.language):  # "yes" to "Did you mean …?"
            suggestion = self.match(question).suggestion
            confirmed = self.match(suggestion) if suggestion else None
            return confirmed if confirmed is not None and confirmed.is_exact else None
        focus = self.choice(answer)
        if not focus:
            return None
        result = self.match(question, focus)
        return result if result.is_exact else None

    def match(self, text: str, focus: Focus = None) -> MatchResult:
        """What ``text`` asks for in this world. Never raises on user input.

        ``focus`` limits the targets to those devices (see :meth:`follow_up`). The literal
        reading comes first; everyday phrasings and close guesses after it
        (:func:`rosaos.intents.understanding.generalize.understand`).
        """
        text = tidy(" ".join(text.split()))  # "turn the, um, the lamp off", "play X, volume 30"
        if not text:
            return no_match(self.context, text)
        absent = self._absent_kinds.refusal(text)
        if absent is not None:  # "the fan in the bedroom" with no fan: never the bedroom's lamp
            return MatchResult("no_match", text, reply=absent, refusal=True)
        if says_stop(normalise(text)) and (kept := without_idle(text, self._names_device)) != text:
            return self.match(kept, focus)  # "stop the music, I need to focus": only the stop
        wish = wished(text)
        if wish is not None:
            # A wish is read as its command; if that is not understood, the wish was about a
            # state this device has not (an unknown colour): say so, never change something else.
            meant = self.match(wish.command, focus)
            if meant.kind != "no_match":
                return meant
            reply = f'Sorry, I don\'t know "{wish.state}" as a colour or setting of {wish.device}.'
            return MatchResult("no_match", text, reply=reply, refusal=True)
        return understand(
            text,
            focus,
            self.literal,
            self.context.names,
            self._fuzzy,
            self.language,
            self._whole,
            self._compose,
            self._template,
            self._compose_complete,
        )

    def _names_device(self, text: str) -> bool:
        reference = self._composer.references.resolve(text)
        return reference.named and not reference.unknown

    def _compose(self, text: str, focus: Focus = None) -> MatchResult | None:
        return self._composer.read(text, focus, self._clause_reading)

    def _compose_complete(self, text: str, focus: Focus = None) -> MatchResult | None:
        return self._composer.read(text, focus, self._clause_reading, complete=True)

    def _clause_reading(self, clause: str, focus: Focus) -> Reading | None:
        """One clause read as an exact template match, for the compositional reader."""
        found = self._best(clause, focus)
        return found if found is not None and found.actionable and not self._hides_command(found) else None

    def _whole(self, text: str, focus: Focus = None) -> MatchResult:
        return self._exact(text, focus)

    def _template(self, text: str, focus: Focus = None) -> MatchResult:
        """``text`` as one whole template (one recognition), or "not understood"."""
        whole = self._best(text, focus)
        if whole is None or not whole.actionable or self._hides_command(whole):
            return no_match(self.context, text)
        if whole.rank == RANK_ANY:
            # A template that names no target ("turn off all the lights" for "all the
            # lamps") ignored what the sentence says of its devices; the reader does not.
            composed = self._compose(text, focus)
            if composed is not None and composed.is_exact:
                return composed
        return build_result(self.context, text, [whole], focus is not None)

    def literal(self, text: str, focus: Focus = None) -> MatchResult:
        """``text`` read against the templates as said: whole, split at conjunctions, or elided."""
        template = self._template(text, focus)
        if template.is_exact:
            return template
        whole = self._best(text, focus)
        pieces = self._splitter.split(text)
        if 3 <= len(pieces) <= 2 * MAX_PIECES - 1:
            for allow_unknown in (False, True):
                split = self._partition(tuple(pieces), allow_unknown, focus)
                if split is not None:
                    return build_result(self.context, text, split, focus is not None)
        refused = refuse_bad_number(
            text, lambda sentence: self._exact(sentence, focus), self._display_name, self.context.language
        )
        if refused is not None:
            return refused
        if whole is not None:
            return build_result(self.context, text, [whole], focus is not None)
        unknown = self._unknown_names.reading(text)
        if unknown is not None:
            return build_result(self.context, text, [unknown], False)
        elided = self._elided_anywhere(text, focus)
        if elided is not None:
            return build_result(self.context, text, [elided], focus is not None)
        return no_match(self.context, text)

    # Recognition

    def _readings(self, clause: str, focus: Focus, device: str | None = None) -> list[Reading]:
        """Every reading of ``clause``; with ``device``, only those that could act on it alone:
        its own driver's templates, and HA's only when its driver maps HA intents (another
        driver's templates, or HA's for a robot, cannot yield a call to it)."""
        owner = self.devices[device].driver if device is not None else None
        readings: list[Reading] = []
        for driver in self._drivers:
            if owner is not None and driver.driver != owner:
                continue
            for result in self._recognize(clause, driver.intents, driver.lists):
                action = driver.file.actions[result.intent.name]
                reading = driver_reading(self.context, clause, result, driver.devices, action, focus)
                if reading is not None:
                    readings.append(reading)
        # A driver's own template outranks any HA reading, so HA (the slower, bigger grammar)
        # is only consulted when no driver template settled the clause.
        ha = device is None or device in self.context.mappings
        if self._ha is not None and ha and not any(reading.actionable for reading in readings):
            for result in self._recognize(clause, self._ha, self._ha_lists, ha=True):
                if self._only_names(clause, result):
                    continue
                reading = ha_reading(self.context, clause, result, focus)
                if reading is not None:
                    readings.append(reading)
        return readings

    def _recognize(
        self,
        clause: str,
        intents: Intents,
        lists: dict[str, SlotList],
        ha: bool = False,
        unmatched: bool = False,
    ) -> list[RecognizeResult]:
        results = recognize_all(
            clause,
            intents,
            slot_lists=lists,
            skip_words=self._skip_words,
            intent_context={"area": {"value": NO_AREA}} if ha else None,
            allow_unmatched_entities=unmatched,
            language=self.language,
        )
        return list(itertools.islice(results, MAX_RESULTS_PER_SOURCE))

    def _only_names(self, clause: str, result: RecognizeResult) -> bool:
        """Whether ``clause`` says nothing but the names it matched ("the desk lamp").

        HA's bare "{name}" templates (meant for scenes and scripts) would read a lone device name
        as "turn it on". A command needs a word of its own; a lone name is at most a choice.
        """
        text = clause.lower()
        for entity in result.entities.values():
            if entity.text.strip():
                text = text.replace(entity.text.strip().lower(), " ", 1)
        return all(word in self._filler for word in re.findall(r"[\w']+", text))

    def _best(self, clause: str, focus: Focus, device: str | None = None) -> Reading | None:
        """The best reading of ``clause`` (``device``: see :meth:`_readings`)."""
        # Cached: a split tries the same clauses again, and users repeat themselves.
        key = (clause, focus, device)
        if key not in self._cache:
            if len(self._cache) >= CACHE_SIZE:
                self._cache.pop(next(iter(self._cache)))
            readings = self._readings(clause, focus, device)
            self._cache[key] = max(readings, key=Reading.sort_key) if readings else None
        return self._cache[key]

    def _exact(self, text: str, focus: Focus) -> MatchResult:
        """``text`` as one whole command, or "not understood" (no splitting, no questions)."""
        whole = self._best(text, focus)
        if whole is not None and whole.actionable and not self._hides_command(whole):
            return build_result(self.context, text, [whole], focus is not None)
        return no_match(self.context, text)

    def _display_name(self, device: str) -> str:
        return self.context.devices[device].display_name

    def _hides_command(self, reading: Reading) -> bool:
        """A wildcard that swallowed a conjunction ("play jazz and turn on the lamp"), or one that
        says no words of its own ("play it again": what plays, not a search for "it again")."""
        return any(
            len(self._splitter.split(text)) > 1 or says_nothing(text) or gives_reason(reading.clause, text)
            for text in reading.wildcards
        )

    def _partition(self, pieces: tuple[str, ...], allow_unknown: bool, focus: Focus) -> list[Reading] | None:
        """Cut ``pieces`` (texts and separators, alternating) into the fewest clauses that all match.

        A clause may lean on the one before it (``before``: its device and its text): "... and
        set it to 30 percent" means that device, "... and the desk lamp" means that command.
        """
        texts, separators = pieces[0::2], pieces[1::2]

        @cache
        def clause(start: int, end: int, before: tuple[str, str] | None) -> Reading | None:
            words = [texts[start]]
            for index in range(start + 1, end):
                words += [separators[index - 1], texts[index]]
            joined = " ".join(word for word in words if word.strip())
            if not texts[start].strip() or not texts[end - 1].strip():
                return None
            found = self._best(joined, focus)
            if before is not None and (found is None or not found.actionable):
                found = (
                    self._elided(joined, before[0], focus)
                    or self._same_command(joined, before[0], before[1], focus)
                    or found
                )
            if found is None and allow_unknown:
                found = self._unknown_names.reading(joined)
            return found

        @cache
        def rest(start: int, before: tuple[str, str] | None) -> list[Reading] | None:
            if start == len(texts):
                return []
            # The whole sentence as one clause was tried already: a split has two clauses or more.
            for end in range(len(texts) - (start == 0), start, -1):
                head = clause(start, end, before)
                tail = rest(end, _leaned_on(head)) if head is not None else None
                if head is not None and tail is not None:
                    return [head, *tail]
            return None

        return rest(0, None)


def _leaned_on(reading: Reading | None) -> tuple[str, str] | None:
    """What a following clause may lean on: the one device an exact reading acts on, and the
    command it read (the clause as rewritten for that device, when it was)."""
    if reading is None or not reading.actionable or len(reading.calls) != 1:
        return None
    return next(iter(reading.calls)), reading.clause
