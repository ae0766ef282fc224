"""Scenes: a mood or an activity that means a setting of several devices ("make it cosy", "movie
night", "time to focus").

People name what they are about to do or how a room should feel, not the devices and levels that
make it so. A scene is that meaning, said once for every world: a list of actions (the same
:class:`~rosaos.intents.understanding.compose.actions.Said` a clause gives), each applied to every
device that can do it, in the place the sentence names ("make the lounge cosy"). With no place
said and several devices that could take part, the engine asks which: a room is not guessed. A
device that cannot do an action is left alone; a scene nothing here can set is not read.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from rosaos.intents.understanding.compose.actions import Said
from rosaos.intents.understanding.compose.level_words import WARM_KELVIN


@dataclass(frozen=True)
class Scene:
    """What a mood or an activity sets: actions, in order."""

    name: str
    actions: tuple[Said, ...]


_SCENES: tuple[tuple[re.Pattern[str], Scene], ...] = (
    (
        re.compile(
            r"\b(?:movie|film|cinema|tv|netflix)\s+(?:night|time|mode|evening)\b"
            r"|\b(?:watch|watching|put on|see)\s+(?:a|the|some)\s+(?:movie|film)\b"
        ),
        Scene("movie", (Said("level", {"level": 20}, family="brightness"),)),
    ),
    (
        re.compile(
            r"\b(?:make|get|set|keep)\s+(?:it|things|the \w+(?: room)?|this place|the place|the mood)\s+"
            r"(?:(?:nice|all|really|more|a bit|a little|nice and|all warm and)\s+)?(?:cosy|cozy|snug|relaxing|romantic|mellow|chill)\b"
            r"|\b(?:cosy|cozy|relaxing|romantic|mellow|chill)\s+(?:mode|vibes?|mood|atmosphere|evening|lighting|light)\b"
            r"|\bmood lighting\b|\bwind(?:ing)? down\b"
        ),
        Scene(
            "cosy",
            (
                Said("colour_temperature", {"kelvin": WARM_KELVIN}),
                Said("level", {"level": 40}, family="brightness"),
            ),
        ),
    ),
    (
        re.compile(
            r"\b(?:time to|need to|want to|going to|gonna|let me|i'?ll)\s+(?:focus|concentrate|study|work|read)\b"
            r"|\b(?:focus|study|work|reading)\s+(?:mode|time|session)\b"
        ),
        Scene("focus", (Said("level", {"level": 100}, family="brightness"),)),
    ),
)  # fmt: skip


def read_scene(text: str) -> Scene | None:
    """The scene ``text`` names, if any (``text`` normalised: lowercase, digits)."""
    return next((scene for pattern, scene in _SCENES if pattern.search(text)), None)
