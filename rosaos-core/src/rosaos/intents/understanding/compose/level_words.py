"""The light and sound words of the action lexicon: colours, white's warmth, levels, on and off.

Split out of :mod:`~rosaos.intents.understanding.compose.actions`, whose
:func:`~rosaos.intents.understanding.compose.actions.read_action` tries these after the robots'
and the player's own words.
"""

from __future__ import annotations

import re

from rosaos.intents.understanding.compose.quantities import Quantity, Size
from rosaos.intents.understanding.compose.said import SIZES, Said
from rosaos.intents.understanding.compose.said import TURN_VERB as _TURN_VERB
from rosaos.intents.understanding.compose.said import cut as _cut

_COOLER = re.compile(r"\b(?:cooler|colder|bluer|whiter|crisper|less warm|less yellow)\b")
_WHITE = re.compile(r"\b(?:(?:shade|tone|kind)\s+of\s+)?(?:white|yellow|daylight)\b")
_WARMER = re.compile(r"\b(?:warmer|cozier|cosier|yellower|softer white|less cool|less blue|more yellow)\b")
_WARM = re.compile(r"\b(?:warm|cozy|cosy|candle-?like)\b")
_COOL = re.compile(r"\b(?:cool|cold|crisp|icy)\b")
WARM_KELVIN, COOL_KELVIN = 2700, 5500
_VOLUME_WORD = re.compile(r"\b(?:volume|loud\w*|quiet\w*|soft\w*|sound|music|noise)\b")
_LEVEL_NOUN = re.compile(r"\b(?:volume|loud\w*|quiet\w*|soft\w*|sound)\b")
_BRIGHT_WORD = re.compile(r"\b(?:bright\w*|dim\w*|dark\w*|lighter|light level)\b")
_UP = re.compile(
    r"\b(?:up|brighter|brighten|lighter|louder|raise|increase|boost|crank|pump|more|higher|amp)\b"
)
_DOWN = re.compile(
    r"\b(?:down|dim|dimmer|darker|quieter|softer|lower|decrease|reduce|less|tone|knock|turn down|"
    r"dimmed|not so loud|not so bright)\b"
)
_MAX = re.compile(
    r"\b(?:max(?:imum|ed|ed out)?|full(?:\s+(?:brightness|volume|blast|power))?|all the way up|100 percent"
    r"|as (?:bright|loud|high|much) as (?:it|they|you) (?:goes|go|can go|gets|get|can)|highest(?: setting)?"
    r"|top volume|top brightness)\b"
)
_MIN = re.compile(
    r"\b(?:all the way down|min(?:imum)?|lowest(?: setting)?|as (?:dim|low|quiet|soft) as (?:it|they|you)"
    r" (?:goes|go|can go|gets|get|can))\b"
)
"""The bottom of a level: the relative tool's floor (a bulb stays lit at 1 %, a speaker goes to 0)."""
_SET_WORD = re.compile(r"\b(?:to|at)\s+[\d.]+|\b(?:brightness|volume|level|percent)\b|%")
OFF = re.compile(r"\b(?:off|kill|shut|out|extinguish|cut|deactivate|disable|power down)\b")
_ON = re.compile(
    r"\b(?:turn|switch|put|power|flick|click|flip|get|leave)\s+on\b|\bon$|\bon\b(?!\s+(?:the|my|our|its|your|a|an|top|to)\b)"
    r"|\b(?:light up|power up|activate|enable|illuminate|fire up)\b"
)
_SHARE = re.compile(
    r"\b(?:louder|quieter|brighter|dimmer|darker|softer|up|down|more|less|in|cut|halve\w*|double\w*)\b"
)
"""Words that make a fraction a share of the current level, not a level: "a third louder"."""
_TOGGLE = re.compile(r"\b(?:toggle|flip)\b")


def read_light_or_sound(
    text: str, quantity: Quantity | None, size: Size, colours: frozenset[str]
) -> Said | None:
    if quantity is not None and quantity.unit == "kelvin":
        return Said(
            "colour_temperature",
            {"kelvin": quantity.value},
            _cut(text, re.compile(r"\b(?:colou?r temperature|temperature)\b")),
        )
    coloured = read_colour(text, colours)
    if coloured is not None:
        return coloured
    if _WARMER.search(text):
        return Said(
            "colour_temperature",
            {"kelvin_change": -SIZES["kelvin_change"][size]},
            _cut(text, _WARMER, _WHITE),
        )
    if _COOLER.search(text):
        return Said(
            "colour_temperature", {"kelvin_change": SIZES["kelvin_change"][size]}, _cut(text, _COOLER, _WHITE)
        )
    if _WARM.search(text) and not _COOL.search(text):
        return Said("colour_temperature", {"kelvin": WARM_KELVIN}, _cut(text, _WARM))
    if _COOL.search(text) and not _WARM.search(text):
        return Said("colour_temperature", {"kelvin": COOL_KELVIN}, _cut(text, _COOL))
    family = "volume" if _VOLUME_WORD.search(text) and not _BRIGHT_WORD.search(text) else None
    family = (
        "brightness"
        if _BRIGHT_WORD.search(text) and family is None and not _VOLUME_WORD.search(text)
        else family
    )
    level_words = (
        _MAX,
        _MIN,
        _UP,
        _DOWN,
        _LEVEL_NOUN,
        _BRIGHT_WORD,
        re.compile(r"\b(?:to|at|by|level|percent)\b|%"),
    )
    if _MAX.search(text):
        return Said("level", {"level": 100}, _cut(text, *level_words), family)
    if _MIN.search(text):
        return Said("level", {"change": -100}, _cut(text, *level_words), family)
    if (
        quantity is not None
        and quantity.unit in (None, "percent")
        and (_SET_WORD.search(f"{text} {quantity.text}") or quantity.is_fraction or family)
    ):
        if quantity.is_fraction and _SHARE.search(text) and not re.search(r"\b(?:to|at|by)\b", text):
            return None  # "a third louder", "cut it in half": a share of a level this reader cannot see
        value = quantity.value * 100 if quantity.is_fraction else quantity.value
        if re.search(r"\bby\b", text) and (_UP.search(text) or _DOWN.search(text)):
            change = -value if _DOWN.search(text) else value
            return Said("level", {"change": change}, _cut(text, *level_words), family)
        if 0 <= value <= 100:
            return Said("level", {"level": round(value)}, _cut(text, *level_words), family)
        return None  # a level out of range is refused by the engine's range check, never clipped
    down, up = _DOWN.search(text), _UP.search(text)
    switched_on = up and not family and re.search(r"\b(?:light up|power up|fire up)\b", text)
    if (down or up) and not (OFF.search(text) and not down) and not switched_on:
        change = SIZES["change"][size] * (-1 if down else 1)
        return Said("level", {"change": change}, _cut(text, *level_words), family)
    if OFF.search(text):
        return Said("switch_off", rest=_cut(text, OFF, _TURN_VERB, re.compile(r"\b(?:switch|put|power)\b")))
    if _ON.search(text):
        return Said("switch_on", rest=_cut(text, _ON, _TURN_VERB, re.compile(r"\b(?:switch|put|power|on)\b")))
    if _TOGGLE.search(text):
        return Said("toggle", rest=_cut(text, _TOGGLE))
    return None


_SHADE = re.compile(r"\b(?:plain|pure|normal|regular|simple|nice|bright|back|colou?r|white)\b")
"""Words around a colour name that say no more than it: "back to plain daylight white"."""


def read_colour(text: str, colours: frozenset[str]) -> Said | None:
    """The colour ``text`` names (the longest name the world's lights know), if any; none for a
    white said with a comparative ("a cooler white", "a warmer shade of white"): that changes the
    white the light has, relative to it."""
    if (_WARMER.search(text) or _COOLER.search(text)) and _WHITE.search(text):
        return None
    for colour in sorted(colours, key=len, reverse=True):
        pattern = re.compile(rf"\b{re.escape(colour)}\b")
        if pattern.search(text):
            return Said("colour", {"colour": colour}, _cut(text, pattern, _SHADE))
    return None
