"""Self-corrections and learners' comparatives, rewritten before any reading.

- **A self-correction** ("turn on the kitchen, no sorry, the bedroom light", "set the volume to 30,
  I mean 40"): a correction marker after a first attempt means what follows *replaces* what it
  corrects. A whole command (it starts with a verb) replaces the first attempt; a fragment
  replaces the matching slot of the first attempt (a number, a colour, a direction, a level, or a
  device said with a determiner). Only the corrected command is read: running the first attempt
  would be a wrong change. A correction this module cannot place leaves the sentence as it was,
  for the rest of the engine to read or refuse ("turn on the lamp, no rush" is no correction).
- **"more"/"less" + an adjective** ("make more quiet", "less loud", "too much loud"): the
  comparative the learner meant, so the step goes in the meaning's direction ("more quiet" is
  quieter, never louder; "less warm" is cooler).
"""

from __future__ import annotations

import re

_MARKER = (
    r"(?:no+\s+wait|no+|nope|wait|oh+|sorry|oops|i\s+mean|i\s+meant|actually|rather|or\s+rather"
    r"|make\s+that|scratch\s+that|u+h+|u+m+|e+r+m*)"
)
_REAL = r"(?:no+|nope|sorry|oops|i\s+mean|i\s+meant|actually|rather(?!\s+than)|make\s+that|scratch\s+that)"
_CORRECTION = re.compile(
    rf"^(?P<first>.+?)(?:\s*[,;]|\s*\.\.\.|\s+-+|\s*!)\s*(?:{_MARKER}[\s,.!-]+)*{_REAL}\b[\s,.!-]*"
    rf"(?:{_MARKER}\b[\s,.!-]*)*(?P<fix>[\w'].*)$"
    rf"|^(?P<first2>.+?)\s+(?:i\s+mean|or\s+rather)\s*,?\s+(?P<fix2>[\w'].*)$",
    re.IGNORECASE,
)
"""A first attempt, a correction marker set off by punctuation (or "I mean"/"or rather"), the fix."""

_VERB = re.compile(
    r"^(?:(?:please|can\s+you|could\s+you|just)\s+)*(?:turn|switch|set|make|put|play|dim|brighten|look|"
    r"move|go|drive|rotate|raise|lower|open|close|start|pause|resume|stop|skip|change|give|bring|dock|"
    r"undock|say|tell|increase|decrease|reduce|crank|lift|tilt|nod|shake|wave|sit|stand|walk|roll|spin|"
    r"face|come|back|reverse|shuffle|repeat|mute|unmute)\b",
    re.IGNORECASE,
)
_PRONOUN = re.compile(r"\b(?:it|them|that|this)\b", re.IGNORECASE)
_TENS = r"(?:twenty|thirty|forty|fifty|sixty|seventy|eighty|ninety)"
_SLOTS = {
    "number": re.compile(
        rf"\b(?:\d+(?:\.\d+)?|{_TENS}(?:[ -](?:one|two|three|four|five|six|seven|eight|nine))?|"
        r"(?:a\s+|one\s+)?hundred(?:\s+and\s+\w+)?|zero|one|two|three|four|five|six|seven|eight|nine|ten|"
        r"eleven|twelve|fifteen|eighteen)\b",
        re.IGNORECASE,
    ),
    "colour": re.compile(
        r"\b(?:red|orange|yellow|green|blue|purple|violet|pink|white|cyan|magenta|teal|turquoise|"
        r"lavender|indigo|gold|amber|lime)\b",
        re.IGNORECASE,
    ),
    "direction": re.compile(
        r"\b(?:left|right|up|down|forwards?|backwards?|clockwise|counter-?clockwise|anti-?clockwise)\b",
        re.IGNORECASE,
    ),
    "level": re.compile(
        r"\b(?:low|high|dim|bright|full|max|maximum|minimum|half|medium|quiet|loud|warm|cool|cold|dark)\b",
        re.IGNORECASE,
    ),
}
"""What a fragment may correct, in the order they are tried."""
_DETERMINED = re.compile(
    r"\b(?:the|my|our|your|this|that)\s+(?:(?!(?:on|off|to|at|up|down|in|please|and|with|for|now)\b)[\w'-]+"
    r"(?:\s+|$))+",
    re.IGNORECASE,
)
"""A device said with a determiner, up to a particle: "the kitchen light" in "turn the kitchen light on"."""


def corrected(text: str) -> str:
    """``text`` with a self-correction applied (see the module docstring), else unchanged."""
    found = _CORRECTION.match(text)
    if found is None:
        return text
    first = (found.group("first") or found.group("first2")).strip()
    fix = (found.group("fix") or found.group("fix2")).strip().rstrip(" .!")
    verb = _VERB.match(fix)
    if verb is not None and not _PRONOUN.search(fix):
        return corrected(fix)  # a whole new command; it may correct itself again
    slotted = first
    for pattern in _SLOTS.values():
        values = pattern.findall(fix)
        olds = list(pattern.finditer(slotted))
        if values and olds:
            old = olds[-1]
            slotted = f"{slotted[: old.start()]}{values[-1]}{slotted[old.end() :]}"
    if slotted != first:
        return slotted
    if verb is not None:
        return corrected(fix)
    return _device(first, fix) or text


def _device(first: str, fix: str) -> str | None:
    """``first`` with its device phrase replaced by the fragment ``fix`` ("no, the bedroom light")."""
    if not re.match(r"^(?:the|my|our|your)\s+\w", fix, re.IGNORECASE):
        return None
    olds = list(_DETERMINED.finditer(first))
    if not olds:
        return None
    old = olds[-1]
    said = old.group(0).rstrip()
    if re.search(r"\bones?$", fix) and len(said.split()) > 2:  # "no, the bedroom one": its noun
        fix = f"{fix.rsplit(' ', 1)[0]} {said.split()[-1]}"
    tail = first[old.start() + len(said) :]
    return f"{first[: old.start()]}{fix}{tail}"


_MORE = {
    "loud": "louder", "loudly": "louder", "noisy": "louder", "quiet": "quieter", "quietly": "quieter",
    "soft": "quieter", "softly": "quieter", "silent": "quieter", "bright": "brighter",
    "dim": "dimmer", "dark": "darker", "warm": "warmer", "cool": "cooler",
    "cold": "cooler", "high": "higher", "low": "lower",
}  # fmt: skip
"""The comparative a learner means by "more" + an adjective."""
_LESS = {
    "loud": "quieter", "loudly": "quieter", "noisy": "quieter", "quiet": "louder", "quietly": "louder",
    "soft": "louder", "bright": "dimmer", "dim": "brighter", "dark": "brighter", "warm": "cooler",
    "cool": "warmer", "cold": "warmer", "high": "lower", "low": "higher",
}  # fmt: skip
"""The comparative a learner means by "less" + an adjective: the opposite one."""
_COMPARATIVE = re.compile(
    rf"\b(?P<much>(?:a\s+)?(?:(?:little|bit|lot|much)\s+)?(?:bit\s+)?)"
    rf"(?P<how>more|less)\s+(?P<word>{'|'.join(sorted(_MORE, key=len, reverse=True))})\b",
    re.IGNORECASE,
)
_TOO_MUCH = re.compile(
    r"\b(too|so|very)\s+(?:much|many)\s+(?=(?:loud|quiet|bright|dark|dim|warm|cold|cool|noisy)\b)",
    re.IGNORECASE,
)


def comparatives(text: str) -> str:
    """``text`` with "more quiet" as "quieter", "less loud" as "quieter", "too much loud" as "too loud"."""
    text = _TOO_MUCH.sub(r"\1 ", text)

    def comparative(found: re.Match[str]) -> str:
        table = _MORE if found.group("how").lower() == "more" else _LESS
        return f"{found.group('much')}{table[found.group('word').lower()]}"

    return _COMPARATIVE.sub(comparative, text)
