"""Recognising a question about a device's state, answered from its state with no lease.

A question is a question form ("is …", "where is …", "how much …") around a device reference,
resolved from the world's names (:class:`~rosaos.intents.understanding.stop_words.DeviceRefs`),
asking about one :data:`Topic`. The forms are those of the language, not of a driver: "is the
porch light still on?" and "is the turtlebot docked?" need no template of the driver's. A
reference several devices share ("where is the robot?") asks about each of them; a missing one
("how much battery?", "what's playing?") about every device whose state has the answer.

What is around a question never changes what it asks, so it is taken off by its role, as the
command reader does for commands: openers ("oh", "hey, quick question:"), indirect frames ("do
you know if …", "can you tell me whether …": the question inside is read as asked), adverbs of
time ("still", "right now", "at the moment", "currently") wherever they stand, and tags ("…, do
you know?", "… then?").
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Literal

from rosaos.intents.understanding.compose.speech import command_words
from rosaos.intents.understanding.stop_words import DeviceRefs

Topic = Literal[
    "on", "off", "playing", "is_playing", "position", "battery", "docked", "people", "busy", "help",
    "brightness", "colour", "volume",
]  # fmt: skip

_OPENERS = re.compile(
    r"^(?:(?:hey|okay|ok|so|um|uh|oh|ah|hmm|well|rosa|please|quick question|just wondering|just curious)[, ]+)*"
)
_FRAMES = re.compile(
    r"^(?:(?:can|could|would) you (?:please )?tell me|do you (?:happen to )?know|tell me|i wonder|"
    r"i'm wondering|i was wondering|i'd like to know|any idea|have you (?:any|an) idea|let me know|check) "
)
"""What makes a question indirect: "do you know …", "can you tell me …" (its inner question is read)."""
_NOT_A_NOUN = r"(?!(?:the|a|an|my|our|your|this|that|these|those|its|it)\b)"
_INDIRECT = re.compile(
    r"^(?:if|whether) (?P<ref>.+?) (?P<verb>is|are|has|was|were|does|did) (?P<rest>.+)$"
    rf"|^(?P<wh>what(?: {_NOT_A_NOUN}\w+)?|which \w+|how \w+|where|who) (?P<ref2>.+) (?P<verb2>is|are)"
    r"(?: (?P<tail>set to|at|on|playing|doing|set at))?$"
)
"""An indirect question ("… if the lamp is on", "… what colour the lamp is") → asked directly."""
_TIME_WORDS = re.compile(
    r"\b(?:still|currently|presently|right now|at the moment|at present|just now|by any chance|already|now)\b"
    r"|\b(?:sitting|standing|resting|parked|back)\b(?= (?:on|at|in|by)\b)"
)
"""Words that say when or how, not what is asked: "is the robot still sitting on its dock?"."""
_TAGS = re.compile(
    r"(?:[, ]+(?:do you know|you know|any idea|then|please|for me|by any chance|can you check|"
    r"could you check|or not|right|currently|now))+$"
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
    ("is_playing", r"is (?:the )?(?:music|song|playlist|track) (?:going|playing|on|running)" + _NOW),
    ("is_playing", rf"is {_REF} (?:going|running|still going){_NOW}"),
    ("position", rf"(?:where is|where's|wheres|where are) {_REF}{_NOW}"),
    ("position", rf"(?:what is|what's|whats) {_REF}(?:'s)? (?:position|location)"),
    ("position", rf"where (?:did|has) {_REF} (?:go|gone|get to|got to|end up|ended up|wind up|wound up|land|landed|get|got)"),
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
    ("on", rf"did (?:i|we|you|someone|somebody|anyone|anybody) (?:leave|forget|keep) {_REF} (?:on|lit|running)"),
    ("off", rf"did (?:i|we|you|someone|somebody|anyone|anybody) (?:turn|switch|shut) off {_REF}"),
    ("off", rf"did (?:i|we|you|someone|somebody|anyone|anybody) (?:turn|switch|shut) {_REF} off"),
    ("on", rf"(?:is|are) {_REF} (?:switched |turned )?(?:on|lit)(?: or (?:off|not))?"),
    ("brightness", rf"how (?:bright|dim|brightly lit) (?:is|are) {_REF}(?: set| turned up)?(?: to| at)?"),
    ("brightness", rf"(?:what|which) (?:brightness|level|percentage|percent|dimmer level) (?:is|are) {_REF}(?: set| turned| dimmed)?(?: to| at| on)?"),
    ("brightness", rf"(?:what's|whats|what is|how's|hows|how is) the (?:brightness|dimmer|light level)(?: level)?(?: (?:of|on|for) {_REF})?(?: set)?(?: to| at)?"),
    ("brightness", rf"(?:what's|whats|what is|how's|hows|how is) {_REF}(?:'s)? (?:brightness|dimmer|light level)(?: level)?(?: set)?(?: to| at)?"),
    ("brightness", rf"(?:what|how much) (?:is|are) {_REF} (?:dimmed|brightened) to"),
    ("colour", rf"(?:what|which) (?:colou?r|shade|hue)(?: temperature)? (?:is|are) {_REF}(?: set| showing| glowing| shining| lit| turned)?(?: to| at| in| on)?(?: (?:right )?now)?"),
    ("colour", rf"(?:what's|whats|what is) the (?:colou?r|shade|hue)(?: temperature)?(?: (?:of|on|for) {_REF})?(?: set)?(?: to| at)?"),
    ("colour", rf"(?:what's|whats|what is) {_REF}(?:'s)? (?:colou?r|shade|hue)(?: temperature)?(?: set)?(?: to| at)?"),
    ("volume", rf"(?:what's|whats|what is|how's|hows|how is) the (?:volume|sound level)(?: level)?(?: (?:of|on|for) {_REF})?(?: set)?(?: to| at)?"),
    ("volume", rf"(?:what's|whats|what is|how's|hows|how is) {_REF}(?:'s)? (?:volume|sound level)(?: level)?(?: set)?(?: to| at)?"),
    ("volume", rf"(?:what|which) volume (?:is|are) {_REF}(?: set| playing| turned)?(?: to| at| on)?"),
    ("volume", r"(?:what|which) volume (?:is|are) (?:it|this|that|the music)(?: set| playing| turned)?(?: to| at| on)?"),
    ("volume", rf"how loud (?:is|are) {_REF}(?: set| playing| turned up)?(?: to| at)?"),
    ("volume", r"how loud (?:is|are) (?:it|this|that)(?: set| playing| turned up)?(?: to| at)?"),
    ("playing", r"(?:what|which|who)(?:'s| is| are)? .*\b(?:song|track|tune|music|playing|singing|artist|band|album|listening to|on the (?:radio|speaker|stereo))\b.*"),
    ("help", r"(?:.+ )?what (?:kind of |kinds of |sort of |sorts of )?(?:things |stuff )?(?:can|could) (?:you|i) (?:do|say|ask|tell you to do)(?: here| for me| with you)?"),
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
    said = " ".join(text.lower().replace("’", "'").replace("?", " ").replace(",", " , ").split()).strip(
        " .!,"
    )
    said = _OPENERS.sub("", _TAGS.sub("", said)).strip(" ,")
    indirect = _FRAMES.match(said)
    if indirect is not None:
        said = _direct(said[indirect.end() :].strip(" ,"))
    said = " ".join(_TIME_WORDS.sub(" ", said).replace(",", " ").split())
    # The discourse around a question ("hmm, …", "ok so …", "… then?") is the command reader's to strip.
    bare = command_words(said)
    # "is the lamp on or did someone turn it off?": the first alternative is asked, the state answers both
    first = said.split(" or ", 1)[0] if " or " in said else None
    for topic, form in FORMS:
        found = form.match(said) or (form.match(bare) if bare != said else None)
        if found is None and first:
            found = form.match(first)
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


def _direct(said: str) -> str:
    """An indirect question as a direct one: "if the lamp is on" → "is the lamp on", "what colour
    the lamp is" → "what colour is the lamp"; anything else as it is."""
    found = _INDIRECT.match(said)
    if found is None:
        return said
    if found.group("ref"):
        return f"{found.group('verb')} {found.group('ref')} {found.group('rest')}"
    tail = f" {found.group('tail')}" if found.group("tail") else ""
    return f"{found.group('wh')} {found.group('verb2')} {found.group('ref2')}{tail}"


def _devices(ref: str, refs: DeviceRefs) -> tuple[str, ...] | None:
    words = ref.split()
    if words and words[0] in ("you", "yourself"):
        return None
    if words and words[-1] in ("it", "that", "this", "there"):
        return None
    return refs.resolve(ref)
