"""Recognising a question about a device's state, answered from its state with no lease.

A question is a question form ("is …", "where is …", "how much …") around a device reference,
resolved from the world's names (:class:`~rosaos.intents.understanding.stop_words.DeviceRefs`),
asking about one :data:`Topic`. The forms are those of the language, not of a driver: "is the
porch light still on?" and "is the turtlebot docked?" need no template of the driver's. A
reference several devices share ("where is the robot?") asks about each of them; a missing one
("how much battery?", "what's playing?") about every device whose state has the answer.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Literal

from rosaos.intents.understanding.compose.speech import command_words
from rosaos.intents.understanding.stop_words import DeviceRefs

Topic = Literal[
    "on", "off", "playing", "is_playing", "position", "battery", "docked", "people", "busy", "help"
]

_OPENERS = re.compile(
    r"^(?:(?:hey|okay|ok|so|um|uh|rosa|please|quick question)[, ]+)*"
    r"(?:(?:can|could) you tell me |do you know |tell me |i wonder |i'd like to know )?"
)
_REF = r"(?P<ref>[a-z0-9' ]+?)"
_NOW = r"(?: (?:right now|now|at the moment|currently|yet|so far|still))?"
_SEEN = r"(?:anyone|anybody|someone|somebody|a person|people|any people|a human|humans|any humans)"

_FORMS: tuple[tuple[Topic, str], ...] = (
    ("on", rf"(?:is|are) {_REF} (?:still |currently )?(?:on|lit|switched on|turned on){_NOW}"),
    ("off", rf"(?:is|are) {_REF} (?:still |currently )?(?:off|switched off|turned off|out){_NOW}"),
    ("playing", rf"(?:what's|whats|what is) (?:playing|on)(?: on {_REF})?{_NOW}"),
    ("playing", r"what (?:song|track|music) is (?:this|that|playing|on)(?: now)?"),
    ("playing", r"(?:who|what) is (?:this|singing|playing)"),
    ("playing", r"what (?:am i|are we|are you|is this|is that) (?:listening to|hearing|playing)"),
    ("playing", r"(?:who's|whos|who is|what's|whats|what is) (?:this|that|it|singing|playing)(?: song| track| tune)?(?: by| called)?"),
    ("playing", r"(?:what|which) (?:song|track|tune|artist|band|album) is (?:this|that|it|playing|on)(?: now)?"),
    ("playing", r"(?:who|what) (?:sings|plays|is singing|is playing) (?:this|that|it)(?: song| track)?"),
    ("is_playing", r"is (?:there )?(?:any )?(?:music|anything|something) (?:playing|on)" + _NOW),
    ("is_playing", rf"is {_REF} playing(?: anything| something| music)?{_NOW}"),
    ("position", rf"(?:where is|where's|wheres|where are) {_REF}{_NOW}"),
    ("position", rf"(?:what is|what's|whats) {_REF}(?:'s)? (?:position|location)"),
    ("position", rf"where (?:did|has) {_REF} (?:go|gone|get to|got to)"),
    ("battery", rf"how much (?:battery|charge)(?: (?:does|has|is) {_REF}(?: have| got)?)?(?: left)?{_NOW}"),
    ("battery", rf"how (?:charged|full) is {_REF}{_NOW}"),
    ("battery", rf"(?:what's|whats|what is|how's|hows|how is) {_REF}(?:'s)? (?:battery|charge)(?: level)?"),
    ("battery", rf"(?:what's|whats|what is|how's|how is) the (?:battery|charge)(?: level)?(?: (?:of|on) {_REF})?"),
    ("battery", rf"is {_REF} (?:low on battery|charged|fully charged|running low)"),
    ("docked", rf"is {_REF} (?:docked|on (?:its|the) (?:dock|charger)|charging|back on (?:its|the) dock|at (?:its|the) dock){_NOW}"),
    ("docked", rf"(?:has|did) {_REF} dock(?:ed)?{_NOW}"),
    ("people", rf"(?:does|can|did|has) {_REF} (?:see|seen|spot|spotted|find|found|detect|detected) {_SEEN}{_NOW}"),
    ("people", rf"(?:is|are) (?:there )?{_SEEN} in front of {_REF}"),
    ("people", rf"who (?:does|can|did) {_REF} see{_NOW}"),
    ("busy", rf"is {_REF} (?:moving|walking|driving|busy|doing anything|working){_NOW}"),
    ("help", r"what (?:can|could) (?:you|i) (?:do|say|ask|tell you to do)(?: here| for me| with you)?"),
    ("help", r"(?:help|what do you do|what are you able to do|what commands do you know)"),
)  # fmt: skip
FORMS: tuple[tuple[Topic, re.Pattern[str]], ...] = tuple(
    (topic, re.compile(f"^{form}$")) for topic, form in _FORMS
)
"""A topic for each question form; ``ref`` is the device reference when the form has one."""


@dataclass(frozen=True)
class Question:
    """A question about device state: its topic, and the devices it asks about (empty: any that can say)."""

    topic: Topic
    devices: tuple[str, ...]


def read_question(text: str, refs: DeviceRefs) -> Question | None:
    """The question ``text`` asks, or None when it is not one of the state questions."""
    said = " ".join(text.lower().replace("’", "'").replace("?", " ").replace(",", " ").split()).strip(" .!")
    said = _OPENERS.sub("", said).strip()
    # The discourse around a question ("hmm, …", "ok so …", "… then?") is the command reader's to strip.
    bare = command_words(said)
    for topic, form in FORMS:
        found = form.match(said) or (form.match(bare) if bare != said else None)
        if found is None:
            continue
        ref = found.groupdict().get("ref")
        if not ref:
            return Question(topic, ())
        devices = _devices(ref, refs)
        if devices is None:
            continue  # "is the kettle on?": not a device of this world; the engine says what exists
        return Question(topic, devices)
    return None


def _devices(ref: str, refs: DeviceRefs) -> tuple[str, ...] | None:
    words = ref.split()
    if words and words[0] in ("you", "yourself"):
        return None
    if words and words[-1] in ("it", "that", "this", "there"):
        return None
    return refs.resolve(ref)
