"""Home Assistant's built-in sentence templates, cut down to what this world's drivers map.

``home_assistant_intents.get_intents(language)`` returns the whole hassil file of a language:
about forty intents over every HA domain (covers, locks, timers, ...). The engine keeps only the
intents some driver maps (see :mod:`rosaos.intents.grammar.ha_mapping`), and within them only the template
blocks whose domain is one of the drivers' domains and whose lists the engine can fill. That keeps
recognition fast (a few milliseconds) and stops "open the garage door" from matching a light.

HA templates name their target three ways, and rosaOS fills each from the world:

- ``{name}``: every spoken name of every mapped device, with ``{"domain": ...}`` context;
- ``{area}``: every area of those devices;
- no target at all ("pause the music"): HA then needs the satellite's area as context. rosaOS
  has no satellite area, so it passes :data:`NO_AREA` and resolves such matches to "the one device
  that can do it", or asks which one when there are several.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from functools import lru_cache
from typing import Any

from hassil import Intents

NO_AREA = "@rosaos:no-area"
"""The area passed as context when the sentence names none: "the device, wherever it is"."""

TARGET_LISTS = frozenset({"name", "area"})
# Only these HassGetState answers fit one device; "are any lights on" / "how many" do not.
SINGLE_DEVICE_RESPONSES = frozenset({"one", "one_yesno"})
_LIST_REFERENCE = re.compile(r"\{(\w+)(?::\w+)?\}")


class HaLanguageUnavailable(LookupError):
    """``home-assistant-intents`` has no templates for the configured language."""


@lru_cache(maxsize=8)
def _raw_intents(language: str) -> dict[str, Any]:
    # The JSON of one language is large (English: ~1 MB); load each once per process.
    from home_assistant_intents import get_intents

    data = get_intents(language)
    if data is None:
        raise HaLanguageUnavailable(f"home-assistant-intents has no language {language!r}")
    return data


def load_ha_intents(
    language: str, intent_names: Iterable[str], domains: Iterable[str], targets: Iterable[str] = TARGET_LISTS
) -> Intents | None:
    """HA's templates for ``language``, restricted to ``intent_names`` and ``domains``.

    ``targets``: the target lists the world can fill (``name``, ``area``); a world with no areas
    drops every template that needs one, which halves recognition time there.
    Returns None when nothing is left (no driver maps an HA intent) or the language is unknown.
    """
    wanted, kept_domains = set(intent_names), set(domains)
    if not wanted or not kept_domains:
        return None
    try:
        raw = _raw_intents(language)
    except HaLanguageUnavailable:
        return None
    fillable = set(raw.get("lists", {})) | (set(targets) & TARGET_LISTS)
    intents: dict[str, Any] = {}
    for name in sorted(wanted & set(raw["intents"])):
        blocks = [
            block for block in raw["intents"][name]["data"] if _fits(name, block, kept_domains, fillable)
        ]
        if blocks:
            intents[name] = {**raw["intents"][name], "data": blocks}
    if not intents:
        return None
    return Intents.from_dict({**raw, "intents": intents})


def _fits(intent: str, block: dict[str, Any], domains: set[str], fillable: set[str]) -> bool:
    """Whether a template block can match one of ``domains`` with lists the engine fills."""
    fixed = (block.get("slots") or {}).get("domain")
    if fixed is not None and fixed not in domains:
        return False
    required = (block.get("requires_context") or {}).get("domain")
    if required is not None:
        allowed = {required} if isinstance(required, str) else set(required)
        if not allowed & domains:
            return False
    if intent == "HassGetState" and block.get("response") not in SINGLE_DEVICE_RESPONSES:
        return False
    used = set(_LIST_REFERENCE.findall(" ".join(block.get("sentences", []))))
    return used <= fillable


def state_word(language: str, list_name: str, value: str) -> str | None:
    """A word for HA state ``value`` ("off") in ``language``, from HA's list ``list_name``
    (``on_off_states``): the one the question's template used, so the answer echoes its terms."""
    try:
        slot_list = _raw_intents(language).get("lists", {}).get(list_name)
    except HaLanguageUnavailable:
        return None
    for item in (slot_list or {}).get("values") or []:
        if isinstance(item, dict) and str(item.get("out")) == value:
            return plain_text(str(item.get("in")))
    return None


def plain_text(template: str) -> str:
    """The simplest sentence a template stands for: optional parts dropped, first alternative kept.

    ``"allumé[e][s]"`` → ``"allumé"``, ``"(cold|cool) white"`` → ``"cold white"``.
    """
    text, previous = template, None
    while text != previous:  # innermost groups first, until nothing changes
        previous = text
        text = re.sub(r"\[[^\[\]]*\]", "", text)
        text = re.sub(r"\(([^()|]*)(?:\|[^()]*)?\)", r"\1", text)
    return " ".join(text.split("|")[0].split())
