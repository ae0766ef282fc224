"""A number no template takes ("set the kitchen light to -5 percent") is refused, not guessed at.

Templates bound their numbers (brightness 0-100, volume 0-100, metres 0-20), so such a sentence
matches nothing, or half-matches and asks a question that cannot be answered. If the same
sentence with an ordinary number in that place is an exact command, the number was the problem:
say so, name the device, and change nothing.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from rosaos.intents.grammar.phrases import phrase
from rosaos.intents.understanding.match_result import MatchResult

NUMBER = re.compile(r"(?<![\w.])(?:(?:minus|negative)\s+|-)?\d+(?:[.,]\d+)?(?![\w.])", re.IGNORECASE)
PROBES = ("50", "1")
"""Ordinary values to try in the number's place: one of them fits nearly every bounded slot."""


def refuse_bad_number(
    text: str, match: Callable[[str], MatchResult], display_name: Callable[[str], str], language: str
) -> MatchResult | None:
    """A refusal naming the number and the device, if ``text`` fails only because of a number."""
    for found in NUMBER.finditer(text):
        for probe in PROBES:
            if probe == found.group(0):
                continue
            fixed = match(text[: found.start()] + probe + text[found.end() :])
            if fixed.is_exact and fixed.processes:
                device = display_name(fixed.processes[0].devices[0])
                reply = phrase(language, "bad_number", value=found.group(0), device=device)
                return MatchResult("no_match", text, reply=reply, refusal=True)
    return None
