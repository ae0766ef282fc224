"""One reading of one clause: which devices a hassil match targets, and the tool calls it means.

A reading is either actionable (``calls`` per device) or an issue: a question back to the user
(which light?) or a refusal (no such device, that device can't do that). Issues never actuate.
Readings are ranked so the most specific interpretation wins: a driver's own template first (its
author said exactly which tool), then an HA template naming the device, then one naming an area,
then one naming no target.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any, TypeAlias

from hassil import RecognizeResult

from rosaos.events.plan import RESULT_PLACEHOLDER, PlanAnswer, PlanStep
from rosaos.intents.grammar.ha_intents import NO_AREA, state_word
from rosaos.intents.grammar.ha_mapping import HomeAssistantMapping
from rosaos.intents.grammar.intents_file import IntentAction
from rosaos.intents.grammar.phrases import join_options, phrase, says_all
from rosaos.intents.grammar.vocabulary import DeviceVocabulary

Focus: TypeAlias = frozenset[str] | None
"""The devices a sentence may target: those the user picked when asked "which one?", or None
for every device. Passed down each call of a matching, never kept on the matcher, so one
sentence's answer cannot leak into the next (or into another task's concurrent match)."""

RANK_DRIVER, RANK_NAME, RANK_AREA, RANK_ANY = 4, 3, 2, 1
TARGET_SLOTS = frozenset({"name", "area", "domain", "device"})
_STATE_LIST = re.compile(r"\{(\w+):state\}")


@dataclass
class Reading:
    """What one recognition result means, in this world."""

    clause: str
    rank: int
    literal: int
    """Characters of template text matched: more means a more specific template."""
    calls: dict[str, list[PlanStep]] = field(default_factory=dict)
    """Device → the tool calls for it, in order. Empty for an issue."""
    answers: dict[str, PlanAnswer] = field(default_factory=dict)
    readouts: set[str] = field(default_factory=set)
    """Devices whose reply is their state read aloud ("what is the kitchen light?")."""
    replies: dict[str, str] = field(default_factory=dict)
    """Device → the reply a driver's question template gives, state keys still to fill."""
    fills_state: set[str] = field(default_factory=set)
    """Devices whose reply or answer has ``{key}`` placeholders for the state the process reads."""
    issue: str | None = None
    """The question or refusal to reply with instead of acting."""
    wildcards: tuple[str, ...] = ()
    """Free text a wildcard slot swallowed ("play {search_query}"): may hide a second command."""

    @property
    def actionable(self) -> bool:
        return self.issue is None and bool(self.calls)

    def sort_key(self) -> tuple[int, int, int]:
        return (int(self.actionable), self.rank, self.literal)


_DESCRIBED = re.compile(
    r"^(?:the|that|this)\s+(?P<what>(?:[\w'-]+\s+){0,3}?[\w'-]+)\s+(?:song|track|tune|number|piece)\b(?P<rest>.*)$",
    re.IGNORECASE,
)
"""A track said by what it is about ("the sun song", "that rain song by …"): no title says "the … song"."""


_WHO = r"(?:we|i|you|they|he|she|i'm|we're|you're|they're|everyone|everybody|people|the\s+kids|the\s+guests|guests)"
_OCCASIONS = (
    r"dinner|lunch|breakfast|brunch|supper|(?:a\s+|the\s+)?party|guests|company|work|working|studying|"
    r"study|homework|reading|cooking|cleaning|(?:a\s+|my\s+|the\s+)?workout|exercise|(?:the\s+)?gym|running|"
    r"(?:the\s+)?drive|driving|(?:a\s+|the\s+)?road\s+trip|(?:the\s+|my\s+)?commute|bedtime|sleep|sleeping|"
    r"focus|focusing|concentration|meditation|yoga|relaxing|relaxation|(?:the\s+)?background|date\s+night|"
    r"movie\s+night|game\s+night|tonight|this\s+evening|the\s+evening|this\s+morning|the\s+morning|"
    r"a\s+while|now|(?:the\s+)?kids|(?:the\s+)?children"
)
_PURPOSES = (
    r"relax|unwind|chill(?:\s+out)?|wind\s+down|focus|concentrate|study|work|sleep|fall\s+asleep|dance|"
    r"wake\s+(?:me\s+|us\s+)?up|cook|read|clean|calm\s+down|cheer\s+(?:me|us)\s+up|set\s+the\s+mood|"
    r"get\s+(?:me\s+|us\s+)?going|work\s+out|get\s+pumped|de-?stress|meditate"
)
_OCCASION = re.compile(
    rf"\s*,?\s+(?:(?:while|whilst|as|when)\s+(?:{_WHO}\s+.+|\w+ing(?:\s+.+)?)"
    rf"|(?:during|for|over|with|in)\s+(?:our\s+|my\s+|the\s+|some\s+)?(?:{_OCCASIONS})(?:\s+(?:tonight|later|time))?"
    rf"|(?:to|so\s+{_WHO}\s+can)\s+(?:help\s+(?:me|us)\s+)?(?:{_PURPOSES})(?:\s+(?:to|by|with))?)$",
    re.IGNORECASE,
)
"""An occasion or purpose after the music ("… while we work", "… for dinner", "… to relax"):
why it is wanted, never words of its title, so the search never gets them."""
_SOME = re.compile(
    r"^(?:(?:something|anything|some\s+(?:music|songs?|tunes?|tracks?))\s+(?:by|from)\s+"
    r"|(?:some|a\s+bit\s+of|a\s+little)\s+(?!(?:by|from)\b))(?=\S)",
    re.IGNORECASE,
)
""""some Miles Davis", "something by the Beatles": how much, not words of a title ("something I
love" is searched whole)."""


def slot_values(result: RecognizeResult) -> dict[str, Any]:
    """Matched slots by name. Whole numbers become ``int``: hassil returns 20.0 for "20 percent"."""
    values: dict[str, Any] = {}
    for name, entity in result.entities.items():
        value = entity.value
        if isinstance(value, float) and value.is_integer():
            value = int(value)
        elif isinstance(value, str):
            value = value.strip()
            if entity.is_wildcard and name.endswith("query"):
                value = search_words(value)
        values[name] = value
    return values


def search_words(query: str) -> str:
    """What to search for in a ``{query}`` a person said: a track said by what it is about ("the
    sun song by the Beatles") is searched by its words ("sun by the Beatles"); a "please" at the
    end is politeness, not part of a title."""
    query = re.sub(r"[\s,]+please$", "", query, flags=re.IGNORECASE)
    query = _SOME.sub("", _OCCASION.sub("", query)) or query
    return _DESCRIBED.sub(r"\g<what>\g<rest>", query)


def wildcard_texts(result: RecognizeResult) -> tuple[str, ...]:
    return tuple(entity.text for entity in result.entities.values() if entity.is_wildcard)


class ReadingContext:
    """The world facts readings are resolved against: devices, names, areas, HA mappings."""

    def __init__(self, devices: dict[str, DeviceVocabulary], language: str) -> None:
        self.devices = devices
        self.language = language
        self.names: dict[str, list[str]] = {}
        """Spoken name → devices answering to it (several means the name is ambiguous)."""
        self.areas: dict[str, list[str]] = {}
        self.mappings: dict[str, HomeAssistantMapping] = {}
        given: dict[str, list[str]] = {}
        for device in devices.values():
            for name in device.spoken_names(language):
                self.names.setdefault(name, []).append(device.name)
            for name in device.own_names(language):
                given.setdefault(name, []).append(device.name)
            for area in device.areas(language):
                self.areas.setdefault(area, []).append(device.name)
            mapping_file = device.mapping_file()
            if mapping_file is not None and mapping_file.homeassistant is not None:
                self.mappings[device.name] = mapping_file.homeassistant
        self.names.update(given)  # a name given to a device beats the same word as another's kind

    def named_in(self, text: str) -> tuple[frozenset[str], list[str]]:
        """Devices ``text`` names (by name or area), and the words left over once names are removed.

        "the kitchen one" → the devices in the kitchen, leftover ``["the", "one"]``.
        """
        text = " ".join(re.sub(r"[^\w' -]", " ", text.lower()).split())
        devices: set[str] = set()
        for table in (self.names, self.areas):
            for name in sorted(table, key=len, reverse=True):
                pattern = rf"(?<!\w){re.escape(name)}(?!\w)"
                if re.search(pattern, text):
                    devices.update(table[name])
                    text = re.sub(pattern, " ", text)
        return frozenset(devices), text.split()

    def display(self, names: list[str]) -> str:
        return join_options([self.devices[name].display_name for name in names], self.language)

    def clarify(self, clause: str, literal: int, rank: int, options: list[str]) -> Reading:
        return Reading(
            clause, rank, literal, issue=phrase(self.language, "clarify", options=self.display(options))
        )

    def capable(self, intent: str, domain: str | None) -> list[str]:
        """Devices whose driver maps HA ``intent``, of ``domain`` when the template fixes one."""
        return [
            name
            for name, mapping in self.mappings.items()
            if intent in mapping.intents and (domain is None or mapping.domain == domain)
        ]


def driver_reading(
    context: ReadingContext,
    clause: str,
    result: RecognizeResult,
    driver_devices: list[str],
    action: IntentAction,
    focus: Focus = None,
) -> Reading | None:
    """The reading of a match against a driver's own template (``{device}`` = its instances).

    ``focus``: the devices the user picked when asked "which one?"; others are out of the question.
    """
    slots = slot_values(result)
    if "device" in slots:
        targets = [name for name in context.names.get(str(slots["device"]), []) if name in driver_devices]
    elif "area" in slots:  # "it's too dark in the kitchen": this driver's instances there
        targets = [name for name in context.areas.get(str(slots["area"]), []) if name in driver_devices]
    else:  # a template with no {device}: it means this driver's only instance, if it has one
        targets = list(driver_devices)
    if focus is not None:
        targets = [name for name in targets if name in focus]
    literal = result.text_chunks_matched
    if not targets or (len(targets) > 1 and not action.every):
        return context.clarify(clause, literal, RANK_DRIVER, targets) if targets else None
    references = action.slot_arguments()
    if not set(references.values()) <= slots.keys():
        return None
    args = {
        name: slots[references[name]] if name in references else value for name, value in action.args.items()
    }
    reading = Reading(
        clause,
        RANK_DRIVER,
        literal,
        calls={device: [PlanStep(device=device, tool=action.tool, args=args)] for device in targets},
        wildcards=wildcard_texts(result),
    )
    if len(targets) > 1:
        return reading
    device = targets[0]
    display = context.devices[device].display_name
    if action.is_question:
        reading.fills_state.add(device)
    if action.answer is not None:
        answer = action.answer
        reading.answers[device] = PlanAnswer(
            when=answer.when,
            yes=answer.yes.replace("{device}", display),
            no=answer.no.replace("{device}", display),
        )
    elif action.reply is not None:
        reading.replies[device] = action.reply.replace("{device}", display)
    return reading


def ha_reading(
    context: ReadingContext, clause: str, result: RecognizeResult, focus: Focus = None
) -> Reading | None:
    """The reading of a match against Home Assistant's templates (``focus`` as in :func:`driver_reading`)."""
    intent = result.intent.name
    slots = slot_values(result)
    domain = slots.get("domain")
    capable = context.capable(intent, str(domain) if domain else None)
    if focus is not None:
        capable = [device for device in capable if device in focus]
    name, area = slots.get("name"), slots.get("area")
    area = None if area == NO_AREA else area
    combination = str((result.intent_metadata or {}).get("slot_combination", ""))
    literal = result.text_chunks_matched
    if name is not None:
        rank, named = RANK_NAME, context.names.get(str(name), [])
        if area is not None:
            named = [device for device in named if device in context.areas.get(str(area), [])]
        targets = [device for device in named if device in capable]
        if named and not targets:
            device = context.devices[named[0]].display_name
            return Reading(
                clause, rank, literal, issue=phrase(context.language, "unsupported", device=device)
            )
        # One name, several devices ("music" for two speakers): ask, unless "all" was said.
        if len(targets) > 1 and (intent == "HassGetState" or not says_all(clause, context.language)):
            return context.clarify(clause, literal, rank, targets)
    elif area is not None:
        rank = RANK_AREA
        targets = [device for device in capable if device in context.areas.get(str(area), [])]
        if not targets:
            options = context.display(capable)
            return Reading(
                clause,
                rank,
                literal,
                issue=phrase(context.language, "unknown", phrase=str(area), options=options),
            )
    else:
        rank, targets = RANK_ANY, capable
        # "all the lights" means every one; "the light" or "pause the music" means the only one.
        every = combination.endswith("all") or says_all(clause, context.language)
        if not every and len(targets) > 1:
            return context.clarify(clause, literal, rank, targets)
    if not targets:
        return None
    reading = Reading(clause, rank, literal, wildcards=wildcard_texts(result))
    for device in targets:
        if not _plan_ha_device(context, reading, result, device, intent, slots):
            display = context.devices[device].display_name
            return Reading(
                clause, rank, literal, issue=phrase(context.language, "unsupported", device=display)
            )
    return reading


def _plan_ha_device(
    context: ReadingContext,
    reading: Reading,
    result: RecognizeResult,
    device: str,
    intent: str,
    slots: dict[str, Any],
) -> bool:
    """Add ``device``'s tool calls for ``intent`` to ``reading``; False if its driver can't do it."""
    mapping = context.mappings[device].intents[intent]
    values = {key: value for key, value in slots.items() if key not in TARGET_SLOTS}
    steps = [
        PlanStep(device=device, tool=action.tool, args=action.fill(values))
        for action in mapping.actions
        if action.applies(values)
    ]
    if not steps:
        return False
    reading.calls[device] = steps
    if intent != "HassGetState":
        return True
    display = context.devices[device].display_name
    asked = values.get("state")
    if asked is None:
        reading.readouts.add(device)
        return True
    expected = mapping.states.get(str(asked))
    if expected is None:
        return False
    language = context.language
    heard = result.entities["state"].text.strip() or str(asked)
    others = [state for state in mapping.states if state != str(asked)]
    list_name = _state_list(result)
    other_word = state_word(language, list_name, others[0]) if len(others) == 1 and list_name else None
    no = (
        phrase(language, "no", device=display, state=other_word)
        if other_word
        else phrase(language, "no_not", device=display, state=heard)
    )
    yes = phrase(language, "yes", device=display, state=heard)
    reading.answers[device] = PlanAnswer(when=expected, yes=yes, no=no)
    return True


def _state_list(result: RecognizeResult) -> str | None:
    sentence = result.intent_sentence.text if result.intent_sentence is not None else ""
    match = _STATE_LIST.search(sentence or "")
    return match.group(1) if match else None


def readout_reply(context: ReadingContext, device: str) -> str:
    """The reply of a "what is the X?" question: the device's state, filled in by the process."""
    display = context.devices[device].display_name
    return phrase(context.language, "readout", device=display, result=RESULT_PLACEHOLDER)
