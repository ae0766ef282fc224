"""Quantities as people say them: number words, fractions, mixed numbers, units, vague amounts.

:func:`spell_numbers` rewrites number words as digits first ("two and a half metres" → "2.5
metres", "three quarters" → "0.75", "half a turn" → "0.5 turn"), so the clause splitter never cuts
a number at its "and", and :func:`find_quantity` then reads one ``<number> [unit]`` with the unit
normalised. Vague amounts ("a bit", "way", "slightly") are a size, not a number: :func:`vague_size`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Literal

Size = Literal["small", "normal", "large"]

_UNITS_WORDS = {
    "zero": 0, "one": 1, "two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7,
    "eight": 8, "nine": 9, "ten": 10, "eleven": 11, "twelve": 12, "thirteen": 13, "fourteen": 14,
    "fifteen": 15, "sixteen": 16, "seventeen": 17, "eighteen": 18, "nineteen": 19,
}  # fmt: skip
_TENS_WORDS = {
    "twenty": 20, "thirty": 30, "forty": 40, "fifty": 50, "sixty": 60, "seventy": 70, "eighty": 80,
    "ninety": 90,
}  # fmt: skip
_SCALES = {"hundred": 100, "thousand": 1000}
_FRACTIONS = {
    "half": 0.5, "halves": 0.5, "third": 1 / 3, "thirds": 1 / 3, "quarter": 0.25, "quarters": 0.25,
    "fourth": 0.25, "fourths": 0.25, "fifth": 0.2, "fifths": 0.2, "tenth": 0.1, "tenths": 0.1,
}  # fmt: skip
_NUMBER_WORD = "|".join(sorted([*_UNITS_WORDS, *_TENS_WORDS, *_SCALES], key=len, reverse=True))
_FRACTION_WORD = "|".join(sorted(_FRACTIONS, key=len, reverse=True))
# A run of number words ("twenty five", "one hundred and twenty", "two thousand seven hundred").
_RUN = re.compile(rf"\b(?:{_NUMBER_WORD})(?:(?:[\s-]+|\s+and\s+)(?:{_NUMBER_WORD}))*\b", re.IGNORECASE)
_DIGITS = r"\d+(?:\.\d+)?"
UNITS: dict[str, str] = {
    "%": "percent", "percent": "percent", "per cent": "percent", "pc": "percent",
    "m": "metre", "metre": "metre", "metres": "metre", "meter": "metre", "meters": "metre",
    "cm": "centimetre", "centimetre": "centimetre", "centimetres": "centimetre",
    "centimeter": "centimetre", "centimeters": "centimetre",
    "mm": "millimetre", "millimetre": "millimetre", "millimetres": "millimetre",
    "millimeter": "millimetre", "millimeters": "millimetre",
    "foot": "foot", "feet": "foot", "ft": "foot", "inch": "inch", "inches": "inch",
    "step": "step", "steps": "step", "pace": "step", "paces": "step",
    "degree": "degree", "degrees": "degree", "deg": "degree", "°": "degree",
    "turn": "turn", "turns": "turn", "rotation": "turn", "rotations": "turn",
    "kelvin": "kelvin", "k": "kelvin",
    "second": "second", "seconds": "second", "sec": "second", "secs": "second",
    "minute": "minute", "minutes": "minute", "min": "minute", "mins": "minute",
}  # fmt: skip
METRES_PER = {
    "metre": 1.0,
    "centimetre": 0.01,
    "millimetre": 0.001,
    "foot": 0.3048,
    "inch": 0.0254,
    "step": 0.25,
}
_UNIT = "|".join(re.escape(unit) for unit in sorted(UNITS, key=len, reverse=True))
_QUANTITY = re.compile(rf"(?<![\w.])(?P<value>-?{_DIGITS})\s*(?P<unit>(?:{_UNIT})(?![\w]))?", re.IGNORECASE)

SMALL = ("a little bit", "a tiny bit", "a little", "a bit", "a tad", "a touch", "slightly", "somewhat",
         "a smidge", "a hair", "a notch", "just a bit", "a wee bit")  # fmt: skip
LARGE = ("a whole lot", "a lot", "lots", "way", "much", "far", "loads", "heaps", "a great deal",
         "way more", "a ton", "significantly")  # fmt: skip
_SMALL = re.compile(r"\b(?:" + "|".join(re.escape(word) for word in SMALL) + r")\b", re.IGNORECASE)
# "all the way up" and "the way I like it" are no amount: "way" after "the" is not "way more".
_LARGE = re.compile(r"(?<!the )\b(?:" + "|".join(re.escape(word) for word in LARGE) + r")\b", re.IGNORECASE)


@dataclass(frozen=True)
class Quantity:
    """A number said in a clause, with its unit (None for a bare number)."""

    value: float
    unit: str | None
    text: str
    """The words it was read from, to remove from the clause."""

    @property
    def is_fraction(self) -> bool:
        """A bare number below one that came from a fraction ("half", "three quarters")."""
        return self.unit is None and 0 < self.value < 1


def _run_value(words: list[str]) -> int | None:
    total, current = 0, 0
    for word in words:
        if word in _UNITS_WORDS:
            current += _UNITS_WORDS[word]
        elif word in _TENS_WORDS:
            current += _TENS_WORDS[word]
        elif word == "hundred":
            current = max(current, 1) * 100
        elif word == "thousand":
            total += max(current, 1) * 1000
            current = 0
        elif word != "and":
            return None
    return total + current


def _spell_run(match: re.Match[str]) -> str:
    words = re.split(r"[\s-]+", match.group(0).lower())
    # "one and two" are two numbers: "and" joins a run only after hundred/thousand.
    pieces: list[list[str]] = [[]]
    for word in words:
        if word == "and" and not (pieces[-1] and pieces[-1][-1] in _SCALES):
            pieces.append([])
            continue
        pieces[-1].append(word)
    spelled = []
    for piece in pieces:
        value = _run_value(piece)
        spelled.append(str(value) if value is not None else " ".join(piece))
    return " and ".join(spelled)


def spell_numbers(text: str) -> str:
    """``text`` with number words, fractions and mixed numbers written as digits."""
    text = re.sub(r"(\d),(\d{3})\b", r"\1\2", text)
    text = _RUN.sub(_spell_run, text)
    # "the one in the kitchen", "that one": a device, not a number.
    text = re.sub(
        r"\b(the|this|that|other|which|each|every|any|no) 1\b(?![.\d]|\s*(?:%|percent))", r"\1 one", text
    )
    # "the kitchen one", "my bedroom one": a device said by its place, not a number
    text = re.sub(
        r"\b((?:the|this|that|my|our|your)\s+[a-z][a-z'-]*) 1\b(?=\s*(?:$|,|\b(?:and|then|in|by|on|off|over|"
        r"next|near|beside|up|down|please)\b))",
        r"\1 one",
        text,
    )
    text = re.sub(r"\b(\d+)\s+point\s+(\d+)\b", r"\1.\2", text, flags=re.I)
    # "2 and a half", "1 and 3 quarters"
    text = re.sub(
        rf"\b({_DIGITS})\s+and\s+(?:an?\s+|({_DIGITS})\s+)?({_FRACTION_WORD})\b",
        lambda m: _number(float(m.group(1)) + float(m.group(2) or 1) * _FRACTIONS[m.group(3).lower()]),
        text,
        flags=re.I,
    )
    # "a half", "one quarter"
    text = re.sub(rf"\b(?:an?|one)\s+(?:(?:and\s+)?a\s+)?({_FRACTION_WORD})\b", r"\1", text, flags=re.I)
    # "3 quarters", "2 thirds"
    text = re.sub(
        rf"\b({_DIGITS})\s+({_FRACTION_WORD})\b",
        lambda m: _number(float(m.group(1)) * _FRACTIONS[m.group(2).lower()]),
        text,
        flags=re.I,
    )
    # "half a metre", "a quarter of a turn", "half" alone
    text = re.sub(
        rf"\b({_FRACTION_WORD})(?:\s+(?:of\s+)?(?:an?|the)(?=\s))?\b",
        lambda m: _number(_FRACTIONS[m.group(1).lower()]),
        text,
        flags=re.I,
    )
    # "a metre", "a degree": one of the unit
    text = re.sub(
        r"\b(?:an?)\s+(metre|meter|foot|centimetre|centimeter|degree|step|turn|second|minute)\b",
        r"1 \1",
        text,
        flags=re.I,
    )
    return text


def _number(value: float) -> str:
    return str(int(value)) if float(value).is_integer() else f"{value:.4g}"


def find_quantity(text: str) -> Quantity | None:
    """The first ``<number> [unit]`` in ``text`` (digits; see :func:`spell_numbers`)."""
    match = _QUANTITY.search(text)
    if match is None:
        return None
    unit = match.group("unit")
    return Quantity(
        float(match.group("value")), UNITS[unit.lower()] if unit else None, match.group(0).strip()
    )


def vague_size(text: str) -> Size:
    """How big a change ``text`` asks for: "a bit" is small, "way"/"a lot" large, else normal."""
    if _SMALL.search(text):
        return "small"
    if _LARGE.search(text):
        return "large"
    return "normal"


def remove_vague(text: str) -> str:
    """``text`` without its vague-amount words (they are not device names)."""
    return _LARGE.sub(" ", _SMALL.sub(" ", text))
