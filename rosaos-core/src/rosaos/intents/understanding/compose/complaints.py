"""Complaints about a setting, and vague levels: what "way too loud" and "nice and dim" ask for.

A complaint names a property a device has and says it is off ("whoa, that's way too loud", "ugh
it's a bit bright in here", "this is too blue"). It asks for a relative change the other way, on
the device that has that property, and its intensifier says how big: "a bit too" is a small step,
"too" a normal one, "way too" a large one (the sizes of :data:`~.actions.SIZES`). The complaint is
read from the *kind* of word, an intensifier before an adjective of loudness, lightness or colour
temperature, never from the sentence it sits in.

A vague level said as what is wanted ("turn it really low", "make the lamp super bright", "nice
and dim") is an absolute level, not a step: the intensifier moves it towards the end of the scale.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from rosaos.intents.understanding.compose.actions import SIZES, Said
from rosaos.intents.understanding.compose.quantities import Size
from rosaos.intents.understanding.compose.speech import command_words, normalise, remark

_SMALL = r"(?:a\s+(?:little\s+|tiny\s+)?bit(?:\s+too)?|a\s+little(?:\s+too)?|a\s+tad(?:\s+too)?|slightly(?:\s+too)?|kinda(?:\s+too)?|somewhat(?:\s+too)?)"
_LARGE = r"(?:way\s+too|far\s+too|much\s+too|waa+y\s+too|super|insanely|ridiculously|crazy|really\s+really|so\s+so|too\s+too)"
_NORMAL = r"(?:too|so|very|really|quite|pretty|rather|real|kind\s+of\s+too)"
_DIRECTIONS: dict[str, tuple[str, int]] = {
    "loud": ("volume", -1),
    "noisy": ("volume", -1),
    "blaring": ("volume", -1),
    "deafening": ("volume", -1),
    "quiet": ("volume", 1),
    "soft": ("volume", 1),
    "faint": ("volume", 1),
    "bright": ("brightness", -1),
    "glaring": ("brightness", -1),
    "blinding": ("brightness", -1),
    "dark": ("brightness", 1),
    "dim": ("brightness", 1),
    "gloomy": ("brightness", 1),
    "cold": ("colour_temperature", -1),
    "cool": ("colour_temperature", -1),
    "blue": ("colour_temperature", -1),
    "bluish": ("colour_temperature", -1),
    "icy": ("colour_temperature", -1),
    "clinical": ("colour_temperature", -1),
    "warm": ("colour_temperature", 1),
    "yellow": ("colour_temperature", 1),
    "yellowish": ("colour_temperature", 1),
    "orange": ("colour_temperature", 1),
}
"""Adjective → the property it is about, and which way a complaint of it asks to change it (a
colour that is "too cold" asks for a warmer white: a lower colour temperature)."""
_FELT = frozenset({"cold", "cool", "icy", "warm"})
"""Words said of a room as much as of a light: a complaint of the light only when it names one."""
_OF_LIGHT = re.compile(
    r"\b(?:lights?|lamps?|bulbs?|lighting|colou?r|white|glow)\b|^(?:this|that)(?:'s|\s+(?:is|looks|seems))\b"
)
_ADJECTIVE = "|".join(sorted(_DIRECTIONS, key=len, reverse=True))
_COMPLAINT = re.compile(
    rf"\b(?:(?P<small>{_SMALL})|(?P<large>{_LARGE})|(?P<normal>{_NORMAL}))\s+(?P<adjective>{_ADJECTIVE})\b"
    r"(?!\s+(?:light|lights|lighting|white|colou?r|music|song|track|playlist)\b)"
)


def complaint(clause: str) -> Said | None:
    """The relative change a complaint about a setting asks for, or None when ``clause`` is none.

    ``clause`` is normalised (lowercase). "that's way too loud" → volume down by a large step;
    "it's a bit dark in here" → brightness up by a small one; "this is too blue" → a warmer white.
    A colour as a colour ("too blue a light" is still a white too cold) is left to the colour
    words: an adjective followed by a noun of light or music is not read here.
    """
    found = _COMPLAINT.search(clause)
    if found is None:
        return None
    size: Size = "small" if found.group("small") else "large" if found.group("large") else "normal"
    family, direction = _DIRECTIONS[found.group("adjective")]
    if found.group("adjective") in _FELT and not _OF_LIGHT.search(clause):
        return None  # "it's too cold in here" is the room, not the light: no thermostat here
    if family == "colour_temperature":
        return Said("colour_temperature", {"kelvin_change": direction * SIZES["kelvin_change"][size]})
    return Said("level", {"change": direction * SIZES["change"][size]}, family=family)


_LEVELS: dict[str, tuple[str | None, float, float]] = {
    "bright": ("brightness", 80, 100),
    "loud": ("volume", 70, 90),
    "dim": ("brightness", 30, 10),
    "low": (None, 25, 10),
    "quiet": ("volume", 25, 10),
    "soft": ("volume", 25, 10),
}
"""A vague level → its family (None: whichever level the device has) and the level it means,
said plainly ("make it dim") and with an intensifier ("really dim")."""
_STRONG = r"(?:really|very|super|extra|real|ultra)"
_GENTLE = r"(?:nice|fairly|quite|pretty)"
_SETTING_VERB = re.compile(r"^(?:make|set|keep|get|have|turn|put|bring)\b")
_VAGUE_LEVEL = re.compile(
    rf"\b(?P<adjective>{'|'.join(_LEVELS)})"
    r"(?P<place>\s+(?:in|on|at|over|by)\s+(?:here|there|(?:the|my|our)\s+[\w' ]+)|\s+here)?$"
)


def vague_level(clause: str) -> Said | None:
    """The absolute level a vague wish says ("turn the volume really low" → 10 %, "make the lamp
    bright" → 80 %), or None. Only an adjective said last, after an intensifier or a verb of
    setting: "dim the lamp" (a verb, a relative step) and "it's too bright" (a complaint, see
    :func:`complaint`) are not this."""
    found = _VAGUE_LEVEL.search(clause)
    if found is None:
        return None
    before = clause[: found.start()].strip()
    strong = re.search(rf"\b{_STRONG}$", before) is not None
    if not (strong or re.search(rf"\b{_GENTLE}$", before) or _SETTING_VERB.match(clause)):
        return None
    if re.search(r"\b(?:too|so|bit|little|tad|slightly|not|less|more)$", before):
        return None  # "a bit low" is a complaint or a step, never a level
    family, plain, high = _LEVELS[found.group("adjective")]
    if family is None and re.search(r"\b(?:volume|sound|music)\b", clause):
        family = "volume"
    if family is None and re.search(r"\b(?:brightness|lights?|lamps?)\b", clause):
        family = "brightness"
    rest = re.sub(rf"\b(?:{_STRONG}|{_GENTLE}|to|at|on)$", " ", _SETTING_VERB.sub(" ", before))
    rest = re.sub(r"\b(?:the\s+)?(?:volume|brightness|level|sound)\b", " ", rest)
    place = re.sub(r"\b(?:in|on|at|over|by)?\s*(?:here|there)\b", " ", found.group("place") or "")
    return Said(
        "level", {"level": round(high if strong else plain)}, " ".join(f"{rest} {place}".split()), family
    )


_OCCASION = re.compile(
    r"^(?:it's\s+|its\s+)?(?:about\s+)?time\s+(?:to|for)\s+[\w'-]+$|^(?:bedtime|good\s+night)$"
)
""""time to focus", "bedtime": when, one word after "time to" ("time to turn the lamp on" asks)."""
_SETTING = re.compile(
    r"\b(?:lights?|lighting|lamps?|bright\w*|dark\w*|dim\w*|loud\w*|quiet\w*|volume|music|songs?|"
    r"warm\w*|cold\w*|colou?rs?)\b"
)


def idle(clause: str) -> bool:
    """Whether ``clause`` (normalised) only says why, said beside a command: a remark, a need or
    a feeling that names no setting ("I need to concentrate", "it's time to study", "my phone is
    ringing"). Beside a command it is dropped, never run as a command of its own (such a need once
    switched a lamp on). Whether it names a device is the caller's to check; a remark about a
    setting ("the music is too loud") still asks for something."""
    said = remark(clause) or _OCCASION.match(clause) is not None
    return said and complaint(clause) is None and not _SETTING.search(clause)


def without_idle(text: str, names: Callable[[str], bool]) -> str:
    """``text`` without the idle clauses said after its first (:func:`idle`, naming no device by
    ``names``), cut at commas; ``text`` itself when none is."""
    pieces = [piece for piece in re.split(r"\s*[,;]\s*", text) if piece.strip(" .!?")]
    kept = [pieces[0], *(piece for piece in pieces[1:] if not _idle_piece(piece, names))] if pieces else []
    return ", ".join(kept) if len(kept) < len(pieces) else text


def _idle_piece(piece: str, names: Callable[[str], bool]) -> bool:
    plain = command_words(normalise(piece))
    return bool(plain) and idle(plain) and not names(plain)
