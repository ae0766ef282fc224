"""A kind of device the world lacks is refused, never read as another device in the same room.

"Turn on the fan in the bedroom" in a world with a bedroom lamp and no fan once matched
"turn on the … in the bedroom" and switched the lamp on: the room was enough for the loose
readings, and "fan" was dropped as an unknown word. A noun that names a kind of appliance
(fan, heater, TV, blinds, kettle, door …) is the target of the command, so when no device of the
world is called or described by it, the command is refused before any reading, and the reply
says which devices the room does have.

The lexicon is of kinds of things, not of sentences. A kind noun counts only where it is the
object acted on: after a determiner ("the fan", "my bedroom heater"), not inside a place phrase
("the lamp by the door", "drive to the fridge"), not as the subject of a remark ("the TV is too
loud", "I'm watching the TV"). English only; other languages keep their readings.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

from rosaos.intents.understanding.readings import ReadingContext

_KINDS: tuple[str, ...] = (
    "fan", "ceiling fan", "heater", "space heater", "water heater", "radiator", "thermostat",
    "boiler", "fireplace", "air conditioner", "air conditioning", "aircon", "ac", "a/c",
    "humidifier", "dehumidifier", "air purifier", "purifier", "tv", "television", "telly",
    "projector", "blind", "curtain", "shutter", "awning", "vacuum",
    "vacuum cleaner", "hoover", "roomba", "oven", "stove", "cooker", "hob", "microwave", "kettle",
    "toaster", "fridge", "refrigerator", "freezer", "dishwasher", "washing machine", "washer",
    "dryer", "tumble dryer", "coffee maker", "coffee machine", "espresso machine", "blender",
    "door", "garage door", "gate", "lock", "window", "skylight", "sprinkler", "irrigation",
    "lawnmower", "mower", "doorbell", "camera", "computer", "printer", "router", "plug",
    "socket", "outlet", "hair dryer", "pump", "fountain", "aquarium", "fish tank", "hot tub",
    "sauna", "elevator", "arm", "robot arm", "robotic arm", "drone", "quadcopter",
)  # fmt: skip
"""Kinds of appliances a home or lab may have, singular (a plural "s" is read too). Not words
that also name a quality or a time ("shade" of white, "alarm" for seven)."""
_DETERMINERS = frozenset(
    {"the", "my", "our", "your", "a", "an", "this", "that", "these", "those", "all", "both", "every", "some"}
)
_PLACE_PREPOSITIONS = frozenset(
    {"by", "near", "beside", "next", "over", "above", "under", "below", "behind", "at", "opposite",
     "from", "to", "towards", "toward", "into", "past", "around", "of", "with", "for", "front",
     "beneath", "against", "between", "facing"}
)  # fmt: skip
"""Before a determiner, these make the noun a place ("the lamp by the door"), not the target."""
_BE = frozenset({"is", "are", "was", "were", "'s", "isn't", "aren't", "has", "keeps", "seems", "looks"})
_SPEAKERS = frozenset({"i", "we", "you", "they", "he", "she"})
_SPEAKERS_BEING = frozenset({"i'm", "im", "we're", "you're", "they're", "he's", "she's", "it's"})
"""A clause opening "I'm …", "we are …" or "we … -ing" is a remark ("I'm a fan", "we're
watching the TV"); "I want the fan on" stays a command."""
_SEGMENTS = re.compile(r"[,;]|\b(?:because|since|cause|'cause|so|as|while|but|though)\b")
_WORD = re.compile(r"[a-z][a-z/']*")
_IN_ROOM = re.compile(r"\b(?:in|of) (?:the|my|our) ([a-z]+)\b")
_MAX_MODIFIERS = 3
"""Words allowed between the determiner and the kind noun ("the big bedroom ceiling fan")."""


class AbsentKinds:
    """Finds, in a sentence, the kind of device it acts on when no device of the world is one."""

    def __init__(self, context: ReadingContext) -> None:
        self.context = context
        words: set[str] = set()
        for device in context.devices.values():
            texts = [*device.spoken_names(context.language), device.description, *device.aliases]
            texts += [device.area or "", device.name.replace("_", " ")]
            for text in texts:
                words.update(_WORD.findall(text.lower()))
        self._world_words = words
        self._kinds = sorted(
            (kind for kind in _KINDS if not self._in_world(kind)), key=lambda k: -len(k.split())
        )

    def _in_world(self, kind: str) -> bool:
        """Whether some device is called or described by ``kind`` (any of its words, any number)."""
        return any(
            word in self._world_words
            or f"{word}s" in self._world_words
            or word.rstrip("s") in self._world_words
            for word in kind.split()
        )

    def refusal(self, text: str) -> str | None:
        """The reply refusing ``text`` when it acts on a kind of device the world lacks, else None."""
        if self.context.language != "en" or not self._kinds:
            return None
        lowered = text.lower()
        for segment in _SEGMENTS.split(lowered):
            words = _WORD.findall(segment.replace("\u2019", "'"))
            if _remark(words):
                continue
            kind = self._target_kind(words)
            if kind is not None:
                return self._reply(kind, lowered)
        return None

    def _target_kind(self, words: list[str]) -> str | None:
        present = set(words)  # a kind whose noun is not said cannot occur: skip its scan
        for kind in self._kinds:
            parts = kind.split()
            for plural in (False, True):
                said = [*parts[:-1], parts[-1] + ("s" if plural else "")]
                if said[-1] not in present:
                    continue
                for start in _occurrences(words, said):
                    end = start + len(said)
                    if end < len(words) and (words[end] in _BE or words[end] == "of"):
                        continue  # "the TV is too loud", "a fan of jazz": not the command's object
                    if _object_of_command(words, start):
                        return " ".join(said)
        return None

    def _reply(self, kind: str, text: str) -> str:
        room = next(
            (area for area in sorted(self.context.areas, key=len, reverse=True) if _has(text, area)), None
        )
        devices = self.context.areas.get(room, []) if room is not None else []
        if room is None and (said := _IN_ROOM.search(text)) is not None:
            room = said.group(1)
            devices = [
                name
                for name, device in self.context.devices.items()
                if any(_has(spoken, room) for spoken in device.spoken_names(self.context.language))
            ]
        if room is not None and devices:
            there = self._display(devices)
            return f"I have no {kind} in the {room} to control; devices there: {there}. Nothing was changed."
        return (
            f"I have no {kind} to control; devices I can control: "
            f"{self._display(list(self.context.devices))}. Nothing was changed."
        )

    def _display(self, devices: Iterable[str]) -> str:
        return ", ".join(self.context.devices[device].display_name for device in devices)


def _occurrences(words: list[str], said: list[str]) -> list[int]:
    size = len(said)
    return [i for i in range(len(words) - size + 1) if words[i : i + size] == said]


def _object_of_command(words: list[str], start: int) -> bool:
    """Whether the noun at ``start`` follows a determiner (a few modifiers between), and that
    determiner is not inside a place phrase ("by the door") or a remark's subject."""
    for back in range(1, _MAX_MODIFIERS + 2):
        at = start - back
        if at < 0:
            return False
        word = words[at]
        if word in _PLACE_PREPOSITIONS:
            return False
        if word in _DETERMINERS:
            before = words[at - 1] if at > 0 else ""
            return before not in _PLACE_PREPOSITIONS
    return False


def _remark(words: list[str]) -> bool:
    """Whether a clause speaks of someone rather than asks for something (see ``_SPEAKERS``)."""
    if not words:
        return True
    if words[0] in _SPEAKERS_BEING:
        return True
    return words[0] in _SPEAKERS and (
        (len(words) > 1 and words[1] in {"am", "are", "was", "were"}) or any(w.endswith("ing") for w in words)
    )


def _has(text: str, phrase: str) -> bool:
    return re.search(rf"\b{re.escape(phrase)}\b", text) is not None
