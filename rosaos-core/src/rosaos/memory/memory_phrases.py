"""Sentences about memory, read without an LLM: places, facts, aliases, and what to forget.

:func:`read_memory_request` turns a sentence into one request (or None: not about memory). It
knows the stored places, so "go to the kitchen" is a place request only when a kitchen is
known, and "forget the kitchen" deletes the place rather than a fact. :func:`resolve_aliases`
rewrites a sentence with the aliases people gave ("Rex, sit" → "the dog, sit") before the
engine matches it.
"""

from __future__ import annotations

import math
import re
from collections.abc import Collection, Mapping
from dataclasses import dataclass

from rosaos.memory.store import place_key

# The memory tools of the kernel (rosaos.memory.memory_tools), named here, below the tools, so the
# engine's memory turn (rosaos.models.memory_turn) knows their results without importing them.
MEMORY_TOOL_NAMES = (
    "remember_place",
    "list_places",
    "forget_place",
    "go_to_place",
    "remember",
    "recall",
    "forget",
    "recall_sightings",
    "forget_sightings",
    "show_sighting",
)

_NUMBER = r"(?:minus |negative |-)?\d+(?:\.\d+)?"
_SPOT = r"(?:this |the current |my current |your current )?(?:spot|place|position|location|point|pose)"
_GO = r"(?:go|head|drive|walk|move|navigate|return|come back|come|get|run)(?: over| back| on over)?"

_ROBOT = r"(?:(?P<robot>[\w ]+?), )?"
_REMEMBER_HERE = re.compile(
    rf"^{_ROBOT}(?:please )?(?:remember|save|mark|store|call|name)(?: {_SPOT}| here| where you are)"
    r"(?: as| is)? (?P<name>.+)$"
    rf"|^(?:{_SPOT}|here) is (?P<name2>.+)$"
)
_REMEMBER_AT = re.compile(
    rf"^(?:remember that )?(?P<name>.+?) (?:is|are) at (?:x )?(?P<x>{_NUMBER}),? (?:and )?(?:y )?(?P<y>{_NUMBER})"
    rf"(?:,? (?:facing|yaw|heading) (?P<yaw>{_NUMBER})(?: degrees)?)?$"
)
_GO_TO = re.compile(rf"^{_ROBOT}(?:please )?{_GO} to (?P<name>.+?)(?: please)?$")
_LIST = re.compile(
    r"^(?:which|what) places do you know|^(?:list|show|name) (?:the |your |all )?(?:known )?places"
    r"|^where can you go|^what places (?:are there|have you saved)"
)
_FORGET = re.compile(r"^forget (?:about )?(?:that )?(?P<what>.+)$")
_ALIAS = re.compile(r"^(?:call|name) (?P<target>(?:the |my |our )[\w ]+?) (?P<alias>[\w-]+)$")
_ALIAS_IS = re.compile(
    r"^(?P<target>(?:the |my |our )[\w ]+?)(?:'s name)? is (?:called|named|now called) (?P<alias>[\w-]+)$"
)
_MY_NAME = re.compile(r"^(?:my name is|call me|i am called|i'm called) (?P<name>[\w -]+)$")
_PREFERENCE = re.compile(r"^i (?:like|prefer|want) (?P<key>my [\w ]+?) (?:at|to be|on) (?P<value>.+)$")
_REMEMBER_THAT = re.compile(r"^(?:please )?remember that (?P<fact>.+)$")
_LAST_SEEN = re.compile(
    r"^where (?:did|have) you (?:last )?(?:see|seen) (?:someone|somebody|anyone|anybody|a person|people)(?: last)?$"
    r"|^when did you last see (?:someone|somebody|anyone|anybody|a person)$"
)
_BEEN_IN = re.compile(
    r"^(?:has|have) (?:anyone|anybody|someone|somebody) been (?:in|at|near) (?P<place>.+?)(?P<today> today)?$"
)
_SHOW = re.compile(
    r"^(?:(?:please )?show me|let me see)(?: (?:the |that |a |your )?(?:picture|photo|image|pic)"
    r"| (?:him|her|them|it|that|who (?:you saw|it was)))?(?: please)?$"
)
_FORGET_SEEN = re.compile(r"^forget (?:what|everything|who) (?:you(?:'ve| have)? )?(?:saw|seen)$")
_RECALL = re.compile(
    r"^what do you (?:remember|know)(?: about (?P<about>.+))?$|^what(?:'s| is) my name$|^who am i$"
)


@dataclass(frozen=True)
class RememberPlace:
    """Save a place: here (``x`` None) or at the given coordinates."""

    name: str
    x: float | None = None
    y: float | None = None
    yaw: float | None = None
    robot: str | None = None


@dataclass(frozen=True)
class GoToPlace:
    name: str
    robot: str | None = None


@dataclass(frozen=True)
class ListPlaces:
    pass


@dataclass(frozen=True)
class ForgetPlace:
    name: str


@dataclass(frozen=True)
class RememberNote:
    kind: str
    key: str
    value: str


@dataclass(frozen=True)
class Recall:
    about: str | None = None


@dataclass(frozen=True)
class Forget:
    matching: str


@dataclass(frozen=True)
class RecallSightings:
    """ "Where did you last see someone?" (no place), "has anyone been in the kitchen today?"."""

    place: str | None = None
    today: bool = False


@dataclass(frozen=True)
class ForgetSightings:
    pass


@dataclass(frozen=True)
class ShowSighting:
    """ "Show me" (after "where did you last see someone?"): the newest sighting's picture."""


@dataclass(frozen=True)
class UnknownPlace:
    """ "Go to X" with no place X: the reply names the places there are."""

    name: str


MemoryRequest = (
    RememberPlace
    | GoToPlace
    | ListPlaces
    | ForgetPlace
    | RememberNote
    | Recall
    | Forget
    | UnknownPlace
    | RecallSightings
    | ForgetSightings
    | ShowSighting
)


def normalize(text: str) -> str:
    """Lowercase, single spaces, no end punctuation: what the patterns read."""
    return " ".join(text.lower().replace("’", "'").split()).strip(" .!?")


def read_memory_request(text: str, places: Collection[str]) -> MemoryRequest | None:
    """The memory request ``text`` makes, given the known place names (keys); None if none."""
    said = normalize(text)
    if _LIST.match(said):
        return ListPlaces()
    if _LAST_SEEN.match(said):
        return RecallSightings()
    if found := _BEEN_IN.match(said):
        return RecallSightings(_name(found["place"]), bool(found["today"]))
    if _FORGET_SEEN.match(said):
        return ForgetSightings()
    if _SHOW.match(said):
        return ShowSighting()
    if found := _REMEMBER_AT.match(said):
        yaw = math.radians(_number(found["yaw"])) if found["yaw"] else None
        return RememberPlace(_name(found["name"]), _number(found["x"]), _number(found["y"]), yaw)
    if found := _REMEMBER_HERE.match(said):
        return RememberPlace(_name(found["name"] or found["name2"]), robot=found["robot"])
    if found := _GO_TO.match(said):
        name = _name(found["name"])
        if place_key(name) in places:
            return GoToPlace(name, found["robot"])
        return UnknownPlace(name) if places and not found["robot"] else None
    if found := _FORGET.match(said):
        what = found["what"]
        return ForgetPlace(_name(what)) if place_key(what) in places else Forget(what)
    if found := _ALIAS.match(said) or _ALIAS_IS.match(said):
        return RememberNote("alias", found["alias"], found["target"])
    if found := _MY_NAME.match(said):
        return RememberNote("fact", "my name", found["name"].title())
    if found := _PREFERENCE.match(said):
        return RememberNote("preference", found["key"], found["value"])
    if found := _REMEMBER_THAT.match(said):
        return RememberNote("fact", found["fact"], found["fact"])
    if found := _RECALL.match(said):
        return Recall(found["about"])
    return None


def resolve_aliases(text: str, aliases: Mapping[str, str]) -> str:
    """``text`` with every alias (a whole word, any case) replaced by what it names."""
    for alias, target in aliases.items():
        text = re.sub(rf"(?<![\w-]){re.escape(alias)}(?![\w-])", target, text, flags=re.IGNORECASE)
    return text


_AS_LIKED = r"(?:\s+(?:the way i like it|how i like it|like i like it|to my liking|as usual|the usual way|like always))?"


def apply_preferences(text: str, preferences: Mapping[str, str]) -> str:
    """``text`` with a preference filled in where it asks for the thing and says no value.

    "I like my reading light at 40 percent" is kept as a preference (``my reading light`` →
    ``40 percent``); later "set my reading light", "put my reading light how I like it" or "my
    reading light the way I like it" mean "set my reading light to 40 percent". A sentence that
    says its own value ("set my reading light to 80 percent") or does something else with the
    device ("turn off my reading light") is left as it is.
    """
    said = " ".join(text.lower().replace("\u2019", "'").strip(" .!?").split())
    for key, value in preferences.items():
        thing = re.escape(key.lower())
        bare = re.fullmatch(
            rf"(?:please\s+)?(?:(?:can|could|would) you\s+)?(?:set|put|adjust|make|get|do)\s+{thing}{_AS_LIKED}"
            rf"(?:\s+please)?|{thing},?(?:\s+the way i like it|\s+how i like it|\s+as usual)(?:\s+please)?",
            said,
        )
        if bare is not None:
            return f"set {key} to {value}"
    return text


def _name(words: str) -> str:
    """A place name as said, with "the" kept for replies ("the kitchen")."""
    words = words.strip(" ,.'\"")
    return words if words.startswith(("the ", "my ", "our ")) else f"the {words}"


def _number(text: str) -> float:
    text = text.replace("minus ", "-").replace("negative ", "-")
    return float(text)
