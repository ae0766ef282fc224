"""Rooms named by what people do there: "the sleeping room", "where we cook", "the sitting room".

A device's description says "bedroom" or "kitchen"; a person may say the room by its use instead,
or by another common name for it. Before a phrase is resolved, each such wording is replaced by the
room word descriptions use, so the room is matched as a word of its own and never left to a loose
match on "room" (which every room shares: "the sleeping room" once read as "the living room").

The lexicon is of activities, not of sentences: "<activity>ing room|area|space", "the room where
we <activity>", "where the kids <activity>", for any activity below and any pronoun or group of
people. A wording with an activity this table lacks is left alone; the resolver then treats its
unknown word before "room" as a place this world lacks, and does not guess.
"""

from __future__ import annotations

import re

_ACTIVITY_ROOMS: dict[str, str] = {
    **dict.fromkeys(["sleep", "sleeping", "nap", "napping", "rest", "resting"], "bedroom"),
    **dict.fromkeys(["cook", "cooking", "bake", "baking"], "kitchen"),
    **dict.fromkeys(["eat", "eating", "dine", "dining", "breakfast", "dinner"], "dining"),
    **dict.fromkeys(["wash", "washing", "shower", "bathe", "bathing", "bath"], "bathroom"),
    **dict.fromkeys(["work", "working", "study", "studying"], "office"),
    **dict.fromkeys(["sit", "sitting", "relax", "relaxing", "lounge", "lounging", "family", "front"], "living"),
    **dict.fromkeys(["play", "playing", "kid", "kids", "kid's", "kids'", "baby", "baby's", "babies", "children", "children's", "child's"], "nursery"),
    **dict.fromkeys(["park", "parking"], "garage"),
}  # fmt: skip
"""An activity (or who uses the room) → the word descriptions use for that room."""
PLACE_NOUNS = frozenset({"room", "rooms", "area", "space", "spot", "corner", "nook", "quarters", "place"})
"""Nouns every room shares: they say "a place", never which one."""
_WHO = r"(?:we|i|you|they|people|one|the\s+\w+|our\s+\w+|my\s+\w+)"
_ADVERB = r"(?:usually\s+|normally\s+|always\s+|often\s+|all\s+|sometimes\s+)?"
_WHERE = re.compile(
    rf"\b(?:(?:the\s+)?(?:room|area|part\s+of\s+the\s+(?:house|flat|home)|place)\s+)?"
    rf"(?:where|in\s+which)\s+{_WHO}\s+{_ADVERB}(?:go\s+to\s+|do\s+the\s+|have\s+|get\s+)?([a-z'-]+)"
)
_USE_ROOM = re.compile(r"\b([a-z'-]+)\s+(?:room|area|space|corner|nook|quarters)\b")


def name_places(text: str) -> str:
    """``text`` with each room said by its use replaced by the room's own word (lowercase)."""
    text = text.lower()
    if "where" in text or "which" in text:
        text = _WHERE.sub(_where_room, text)
    return _USE_ROOM.sub(_use_room, text)


def _where_room(found: re.Match[str]) -> str:
    room = _ACTIVITY_ROOMS.get(found.group(1))
    return f"the {room}" if room else found.group(0)


def _use_room(found: re.Match[str]) -> str:
    room = _ACTIVITY_ROOMS.get(found.group(1))
    if room is None:
        return found.group(0)
    return (
        room
        if room.endswith("room") or room in {"kitchen", "office", "garage", "nursery"}
        else f"{room} room"
    )
