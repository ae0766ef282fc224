"""From the exact reading of a sentence to what an everyday sentence means: the order of attempts.

:meth:`rosaos.intents.understanding.matching.IntentMatcher.match` calls :func:`understand`, which
tries, in order, and stops at the first that is an exact command:

1. **the sentence as one template** (``template``): a driver's or Home Assistant's template that
   spells the whole sentence out. One recognition: the common case stays cheap;
2. **the compositional reader** (:mod:`rosaos.intents.understanding.compose`), when it reads
   every clause: actions from a lexicon, devices from their names, kinds, places and
   descriptions, quantities with units, fillers peeled off, several clauses; a clear sentence is
   acted on. It reads the whole sentence in one pass, so it comes before the template paths
   below, which rebuild the sentence many ways (each a full recognition, tens of ms);
3. **a negation** ("don't turn on the lamp"): when the rest is an exact command, it is refused by
   name and nothing else is tried (no rephrasing, no guessing);
4. **the literal paths** (``literal``): the sentence split at conjunctions, a number out of a
   device's range refused, a name the world lacks, a device left out ("drive forward one meter");
5. **rephrasings** (:mod:`rosaos.intents.understanding.rephrase`): fillers dropped, a split name
   joined, a name said first or last ("dog, a bit closer") taken as the device the command is for;
6. the reader again, now allowed to drop commentary around a command ("ugh, it's so bright,
   …"); its "which one?" too when the literal reading found nothing;
7. **the fuzzy model** (:mod:`rosaos.intents.understanding.fuzzy`), only when the literal reading
   found nothing at all (a question or a refusal stands): a close guess acts; a weaker one asks
   "Did you mean …?" and does nothing; questions are never guessed into actions, but a question
   guessed as another question is answered (reading state changes nothing).

Everything else keeps the literal result: "which one?", "I don't know …", "not understood".
The reader never reads negations, questions or "stop", and refuses a number out of a device's
range rather than clipping it, so answering first cannot act where a refusal was due.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from rosaos.intents.grammar.phrases import phrase
from rosaos.intents.understanding.fuzzy import ACT_SCORE, ASK_SCORE, FuzzyMatcher
from rosaos.intents.understanding.match_result import MatchResult
from rosaos.intents.understanding.readings import Focus
from rosaos.intents.understanding.rephrase import negated, rephrasings, strip_fillers

Literal = Callable[[str, Focus], MatchResult]
Compose = Callable[[str, Focus], MatchResult | None]
QUESTION_START: dict[str, re.Pattern[str]] = {
    "en": re.compile(
        r"^(is|are|was|were|what|what's|whats|how|where|who|why|when|which|does|do|did|has|have)\b", re.I
    ),
}


def understand(
    text: str,
    focus: Focus,
    literal: Literal,
    names: dict[str, list[str]],
    fuzzy: FuzzyMatcher | None,
    language: str,
    whole: Literal | None = None,
    compose: Compose | None = None,
    template: Literal | None = None,
    compose_first: Compose | None = None,
) -> MatchResult:
    """What ``text`` means (see the module docstring). ``literal`` reads a sentence exactly as
    said (whole, split or elided); ``template`` (default: ``literal``) only as one whole
    template, the cheap first try; ``whole`` (default: ``literal``) only as one whole command,
    which is all a filled-in fuzzy guess needs and is much cheaper. ``compose_first`` is the
    reader asked for a reading of every clause, before the literal paths; ``compose`` the reader
    after them, which may drop commentary around a command."""
    said = (template or literal)(text, focus)
    if said.is_exact:
        return said
    early = compose_first(text, focus) if compose_first is not None else None
    if early is not None and early.is_exact:
        return early
    command = negated(text, language)
    if command is not None:
        meant = literal(command, focus)
        if meant.is_exact:
            clause = command[:1].lower() + command[1:]
            return MatchResult(
                "no_match", text, reply=phrase(language, "negated", clause=clause), refusal=True
            )
    first = said if template is None else literal(text, focus)
    if first.is_exact or command is not None:
        return first
    spoken = [(name, frozenset(devices)) for name, devices in names.items()]
    for rephrased in rephrasings(text, language, spoken):
        narrowed = rephrased.addressed if focus is None else (rephrased.addressed or focus) & focus
        found = literal(rephrased.text, narrowed if rephrased.addressed is not None else focus)
        if found.is_exact:
            return found
        if rephrased.addressed is not None and found.kind == "clarify" and first.kind == "no_match":
            first = found
    composed = compose(text, focus) if compose is not None and not first.refusal else None
    if composed is not None and (composed.is_exact or first.kind == "no_match"):
        return composed
    if fuzzy is None or first.kind != "no_match" or first.refusal:
        return first
    return _guess(text, first, whole or literal, fuzzy, focus, language)


def _guess(
    text: str,
    first: MatchResult,
    literal: Literal,
    fuzzy: FuzzyMatcher,
    focus: Focus,
    language: str,
) -> MatchResult:
    plain = strip_fillers(text, language)
    guess = fuzzy.guess(plain)
    if guess is None or guess.score < ASK_SCORE:
        return first
    meant = literal(guess.sentence, focus)
    if not meant.is_exact:
        return first
    question = QUESTION_START.get(language.split("-")[0])
    asks = question is not None and question.match(plain) is not None
    acts = any(step.tool != "get_state" for process in meant.processes for step in process.plan.steps)
    if (guess.score >= ACT_SCORE and not (asks and acts)) or (asks and not acts):
        # A question answered from state changes nothing: answering beats "Did you mean …?",
        # which would only ask the user to say their question again.
        return meant
    reply = phrase(language, "did_you_mean", suggestion=guess.sentence)
    return MatchResult("clarify", text, reply=reply, suggestion=guess.sentence)
