"""When a template's wildcard swallowed more than a search: words that only point back, or a reason.

Used by :meth:`~rosaos.intents.understanding.matching.IntentMatcher._hides_command` (moved out of
``matching.py``).
"""

from __future__ import annotations

import re

from rosaos.intents.understanding.compose.speech import normalise, remark

_BACK_REFERENCE = frozenset(
    [
        "it",
        "that",
        "this",
        "the",
        "same",
        "song",
        "track",
        "tune",
        "one",
        "again",
        "more",
        "time",
        "once",
        "over",
        "please",
    ]
)


def says_nothing(wildcard: str) -> bool:
    """Whether a wildcard's text only points back at what is there ("it again", "that song")."""
    words = re.findall(r"[\w']+", wildcard.lower())
    return bool(words) and all(word in _BACK_REFERENCE for word in words)


def gives_reason(clause: str, wildcard: str) -> bool:
    """Whether a wildcard ran on past a comma into a reason ("put on something ambient, I need
    to focus"): the search is the words before it. A title with a comma ("Hello, Goodbye")
    names no subject and verb after it."""
    said = " ".join(re.findall(r"[\w']+", normalise(wildcard)))
    return any(
        remark(part.strip()) and said.endswith(" ".join(re.findall(r"[\w']+", part)))
        for part in normalise(clause).split(",")[1:]
    )
