"""What the local-intent engine knows about each device: names people say, its area, its intents.

Names come from the world, never from a sentence list: the instance name with underscores as
spaces (``kitchen_light`` → "kitchen light"), the configured ``aliases``, and names read off the
description when it has the common shape "<thing> in/on/at the <place>": "Floor lamp in the
living room" gives "floor lamp" and "living room lamp". The area is the configured ``area`` (in
the user's language: "cuisine") plus the one the description gives in English ("... in the
kitchen"), so both "kitchen lights" and Home Assistant's French "lumière de la cuisine" work.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from pathlib import Path

from rosaos.config import DeviceConfig
from rosaos.devices.world import DeviceInstance
from rosaos.intents.grammar.intents_file import IntentsFile, load_intents_file
from rosaos.intents.grammar.phrases import kind_synonyms
from rosaos.plugins import DriverRegistry

# Leading articles people put before a name ("the lamp"); stripped so templates' own
# optional article ("[the] {device}") is not needed twice.
ARTICLES = {
    "en": ("the ", "my ", "our ", "a ", "an "),
    "fr": ("le ", "la ", "les ", "l'", "mon ", "ma ", "mes "),
    "de": ("der ", "die ", "das ", "den ", "dem "),
    "es": ("el ", "la ", "los ", "las "),
    "it": ("il ", "lo ", "la ", "i ", "gli ", "le ", "l'"),
    "nl": ("de ", "het "),
}

# "<thing> in the <place>": the description shape drivers' demo worlds and users write.
_PLACED = re.compile(
    r"^(?:an? |the )?(?P<thing>[\w' -]+?) (?P<prep>in|on|at) (?:the |my |our )(?P<place>[\w' -]+)$"
)
_CLAUSE_END = re.compile(r"[,;.(]|\bwith\b|\band\b")
_PLACE_PHRASE = re.compile(r"\s(?:in|on|at|by|near|next to|above|under)\s")
MIN_KIND_LENGTH = 3
MAX_NAME_WORDS = 3


@dataclass(frozen=True)
class DeviceVocabulary:
    """One device instance as the local-intent engine sees it."""

    name: str
    """Instance name, as the kernel and ``launch_process`` use it."""
    driver: str
    description: str = ""
    aliases: tuple[str, ...] = ()
    area: str | None = None
    intents: Path | None = None
    """The driver's ``intents.yaml`` (``DriverSpec.intents``), or None."""
    _files: dict[str, IntentsFile | None] = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def from_instance(cls, instance: DeviceInstance) -> DeviceVocabulary:
        """Build from a world's :class:`~rosaos.devices.world.DeviceInstance`."""
        return cls(
            name=instance.name,
            driver=instance.spec.name,
            description=instance.description,
            aliases=tuple(instance.aliases),
            area=instance.area,
            intents=instance.spec.intents,
        )

    @property
    def display_name(self) -> str:
        """How replies name the device: the instance name, spoken ("kitchen light")."""
        return self.name.replace("_", " ")

    def intents_file(self, language: str) -> IntentsFile | None:
        """The driver's intents in ``language``: ``intents.<lang>.yaml`` next to ``intents.yaml``,
        or ``intents.yaml`` itself when it is in that language."""
        if language not in self._files:
            self._files[language] = _intents_in(self.intents, language)
        return self._files[language]

    def mapping_file(self) -> IntentsFile | None:
        """The ``intents.yaml`` that holds the ``homeassistant:`` mapping (language-independent)."""
        if "*" not in self._files:
            self._files["*"] = _load(self.intents) if self.intents else None
        return self._files["*"]

    @cached_property
    def _described(self) -> tuple[str, str, str] | None:
        """``(thing, preposition, place)`` read off the description, if it has that shape."""
        clause = _CLAUSE_END.split(self.description.strip().lower(), maxsplit=1)[0].strip()
        match = _PLACED.match(clause)
        if match is None:
            return None
        thing, place = match.group("thing").strip(), match.group("place").strip()
        if len(thing.split()) > MAX_NAME_WORDS or len(place.split()) > MAX_NAME_WORDS:
            return None
        return thing, match.group("prep"), place

    def spoken_names(self, language: str) -> list[str]:
        """Every name this device answers to, lowercased, without leading articles.

        Besides its own names, a device answers to its kind ("lamp" for ``living_room_lamp``,
        "robot dog" and "dog" for "Hiwonder PuppyPi quadruped robot dog") and that kind's
        everyday synonyms ("pup"). A kind several devices share is ambiguous, and the engine
        asks which one; a kind only one device has names it.
        """
        names = list(self.own_names(language))
        kinds = _unique(self._kinds())
        names += kinds
        names += [synonym for kind in kinds for synonym in kind_synonyms(language, kind)]
        return _unique(strip_article(name, language) for name in names)

    def own_names(self, language: str) -> list[str]:
        """The names given to this device: its name, aliases and what its description calls it.

        A name given to one device beats the same word heard as another device's kind: with an
        alias "light" on the kitchen light, "light" is the kitchen light, even beside a lamp.
        """
        names = [self.display_name, *self.aliases]
        if self._described is not None:
            thing, preposition, place = self._described
            names += [thing, f"{place} {thing.split()[-1]}"]
            if preposition == "on" and len(place.split()) >= 2:
                # "Music on the living room speaker": the thing it is on is a name of its own.
                names += [place, place.split()[-1]]
        return _unique(strip_article(name, language) for name in names)

    def _kinds(self) -> list[str]:
        """The nouns that say what the device is: the last word of its name and of the head of
        its description ("TurtleBot4 wheeled mobile robot with a camera" → "robot", "mobile robot")."""
        kinds = [self.display_name.split()[-1]] if " " in self.display_name else []
        for alias in self.aliases:
            kinds += [alias.lower().split()[-1]] if " " in alias.strip() else []
        head = _CLAUSE_END.split(self.description.strip().lower(), maxsplit=1)[0]
        head = _PLACE_PHRASE.split(head, maxsplit=1)[0]
        words = re.findall(r"[a-z][\w'-]*", head)
        if words:
            kinds.append(words[-1])
        if len(words) >= 2:
            kinds.append(" ".join(words[-2:]))
        return [kind for kind in kinds if len(kind) >= MIN_KIND_LENGTH]

    def areas(self, language: str) -> list[str]:
        """Areas this device is in: the configured one, and the one its description names."""
        areas = [self.area] if self.area else []
        if self._described is not None and self._described[1] == "in":
            areas.append(self._described[2])
        return _unique(strip_article(area, language) for area in areas)


def strip_article(text: str, language: str) -> str:
    """``text`` lowercased, trimmed, without one leading article of ``language``."""
    text = " ".join(text.lower().split())
    for article in ARTICLES.get(language, ()) + ARTICLES["en"]:
        if text.startswith(article) and len(text) > len(article):
            return text[len(article) :].strip()
    return text


def device_vocabularies(world: Iterable[DeviceInstance]) -> list[DeviceVocabulary]:
    """The engine's view of every instance of a :class:`rosaos.devices.world.World` that can be
    served: a placeholder driver's instance is never served, so the engine neither targets it
    nor offers it in "Devices I can control"."""
    return [DeviceVocabulary.from_instance(instance) for instance in world if instance.spec.implemented]


def sources_from_config(
    devices: Mapping[str, DeviceConfig], registry: DriverRegistry
) -> list[DeviceVocabulary]:
    """Sources straight from ``[devices.NAME]`` tables, without validating driver settings.

    For tools that read a world without serving it (the task benchmark, tests). A driver that is
    not installed contributes names but no intents.
    """
    sources = []
    for name, device in devices.items():
        spec = registry.drivers[device.driver].spec if device.driver in registry.drivers else None
        sources.append(
            DeviceVocabulary(
                name=name,
                driver=device.driver,
                description=device.description or (spec.description if spec else ""),
                aliases=tuple(device.aliases),
                area=device.area,
                intents=spec.intents if spec else None,
            )
        )
    return sources


def _intents_in(path: Path | None, language: str) -> IntentsFile | None:
    if path is None:
        return None
    translated = path.with_name(f"{path.stem}.{language}{path.suffix}")
    if translated.is_file():
        return _load(translated)
    loaded = _load(path)
    return loaded if loaded.language == language else None


def _load(path: Path) -> IntentsFile:
    """``load_intents_file``, once per file (as long as it is unchanged), not once per device.

    A hundred Tapo lamps share one ``intents.yaml``; parsing it a hundred times was most of the
    kernel's start-up CPU. The parsed file is frozen, so the instances share one copy."""
    try:
        stat = path.stat()
    except OSError:
        return load_intents_file(path)  # raises the error that says what is wrong
    return _load_unchanged(path, stat.st_mtime_ns, stat.st_size)


@lru_cache(maxsize=64)
def _load_unchanged(path: Path, mtime_ns: int, size: int) -> IntentsFile:
    return load_intents_file(path)


def _unique(items: Iterable[str]) -> list[str]:
    return list(dict.fromkeys(item for item in items if item))
