"""What a clause asks to be done: a lexicon of verbs, particles and adjectives → an action.

The actions are the ones drivers declare (:data:`rosaos.intents.grammar.capabilities.ACTIONS`),
plus ``level``: "up", "down", "louder", "dim", "to sixty" change whichever level the device has
(brightness for a bulb, volume for a player), so one word list serves every driver. Each rule
reads the *kind* of thing said (a motion verb and a direction, a level word and a quantity), not a
sentence; the words it used are taken out (:attr:`Said.rest`), and what is left names the device.
"""

from __future__ import annotations

import re
from dataclasses import replace

from rosaos.intents.understanding.compose.level_words import OFF as _OFF
from rosaos.intents.understanding.compose.level_words import read_colour as _colour
from rosaos.intents.understanding.compose.level_words import read_light_or_sound as _light_or_sound
from rosaos.intents.understanding.compose.quantities import (
    METRES_PER,
    Quantity,
    Size,
    find_quantity,
    remove_vague,
    vague_size,
)
from rosaos.intents.understanding.compose.said import SIZES, Said
from rosaos.intents.understanding.compose.said import TURN_VERB as _TURN_VERB
from rosaos.intents.understanding.compose.said import cut as _cut
from rosaos.intents.understanding.readings import search_words

DET = r"(?:(?:the|its|his|her|their|your|my|our|a)\s+)?"
_DOCK_PLACE = (
    r"(?:docking station|charging station|charging dock|charging base|home base|dock|base|charger|home)"
)
_UNDOCK = re.compile(
    rf"\bundock\w*\b|\b(?:off|out of|away from|leave|leaves|leaving)\s+{DET}(?:dock|base|charger|charging station)\b"
)
_DOCK = re.compile(
    rf"\b(?:re)?dock\b|\b(?:go|goes|head|come|return|get|send|drive|take|back|park|walk|roll|move)\b(?:\s+\w+){{0,3}}?"
    rf"\s+(?:back\s+)?(?:to|on|onto|into|at|toward|towards)?\s*{DET}{_DOCK_PLACE}\b|\bgo\s+(?:and\s+)?charge\b|\brecharge\b"
    r"|\b(?:back\s+)?to\s+(?:go\s+)?(?:re)?charge\b|\b(?:back\s+)?for\s+(?:a\s+)?(?:re)?charg(?:e|ing)\b"
    r"|\bcharg(?:e|ing)\s+(?:up|itself|yourself|its battery|your battery)\b|\b(?:go|head|get)\s+charging\b"
)
"""Back to the dock: "dock", "return to base", "head home", "go back to the charger", "send it back to
charge", "go recharge", "charge up"."""
_SHUFFLE_OFF = re.compile(r"\b(?:un-?shuffle|stop shuffling|no shuffle|shuffle off|in order)\b")
_SHUFFLE = re.compile(r"\b(?:shuffle|mix(?:\s+\w+){0,3}\s+up|mix it up|randomi[sz]e|random order)\b")
_NEXT = re.compile(r"\b(?:skip\w*|next (?:song|track|tune|one|1)|another (?:song|track|tune))\b|^next$")
_PREVIOUS = re.compile(
    r"\b(?:previous(?:\s+(?:song|track|tune))?|last (?:song|track|tune)|back (?:a|one) (?:song|track|tune)"
    r"|go back(?:\s+to the (?:last|previous))?\s+(?:song|track|tune)|replay (?:the )?(?:last|previous)\w*)\b"
)
_PAUSE = re.compile(r"\bpause\w*\b")
_AUDIENCE = r"(?:everyone|everybody|every1|the room|them|us|people|all|the \w+|y'?all)"
_SAY = re.compile(
    r"^(?:(?:have|get|make|let|ask)\s+(?P<who>.+?)\s+(?:to\s+)?)?"
    rf"(?:say(?:\s+to\s+{_AUDIENCE})?|tell\s+{_AUDIENCE}|announce|let\s+{_AUDIENCE}\s+know|inform\s+{_AUDIENCE}"
    r"|shout|call out|give\s+(?:a|an)\s+(?=shout|announcement))(?:\s+that)?\s+(?!to\s)(?P<text>.+)$"
)
"""Words to say out loud, and who says them: "have Reachy say good night", "let everyone know the
pizza's here", "announce that dinner is ready". "Tell the drone to take off" is an order to
someone, not words to say."""
_MODAL_WHO = re.compile(
    r"^(?:can|could|would|will)\s+(?!you\b|u\b)(?P<who>(?:the\s+|our\s+|my\s+)?[\w'-]+)\s+(?:please\s+)?"
    r"(?=say|tell|announce|shout|call out)"
)
"""A device asked to speak by name ("could the Reachy say hello"): the same as "have the Reachy say"."""
_SLEEP = re.compile(
    r"\b(?:go(?:es)?\s+(?:back\s+)?to\s+(?:sleep|bed)|(?:take|have)\s+a\s+(?:little\s+)?(?:nap|rest|snooze)"
    r"|(?:doze|nod)\s+off|(?:time\s+(?:to|for)|you\s+can|you\s+may)\s+(?:go\s+)?(?:sleep|rest|nap|bed)"
    r"|(?:put|send)\s+(?:[\w'-]+\s+){0,3}to\s+(?:sleep|bed)|(?:sleep|nap|snooze|rest)\s+now)\b|^(?:sleep|nap|snooze|rest)$"
    r"|^(?:sleep\s+(?:well|tight)|sweet\s+dreams|get\s+some\s+(?:rest|sleep|shut-?eye)|bedtime|off\s+to\s+(?:bed|sleep)"
    r"(?:\s+(?:you|with\s+you)(?:\s+go)?)?)$"
)
"""Going to sleep, as a verb phrase: "go to sleep", "take a nap", "you can rest now" (a bare noun
"sleep" is not an order: "I need sleep", "play sleep music")."""
_WAKE = re.compile(r"\bwake\s+(?:[\w'-]+\s+){0,3}?up\b|\bwake\s+up\b|^wake\b|\brise\s+and\s+shine\b")
_PRESS = re.compile(r"\b(?:hit|press|push|tap|click|do|go)\b|\b(?:ahead|forward|on)$")
"""Words around a transport word that add nothing: "hit pause", "skip ahead", "go back a song"."""
_RESUME = re.compile(
    r"\b(?:resume|unpause|un-pause|keep playing|continue playing|continue|carry on|replay)\b"
    r"|\bpick(?:\s+\w+){0,3}?\s+back\s+up\b|\bstart(?:\s+\w+){0,3}?\s+(?:again|back\s+up)\b"
    r"|\bkeep (?:it |the music )?going\b|\b(?:hit|press|push|tap) play\b"
)
_BACK_ON = re.compile(
    r"\b(?:put|turn|switch|flick|get|have|bring|set)\b(?P<what>(?:\s+[\w']+){0,4}?)\s+back\s+on$"
)
"""On again, whatever the device: "put the music back on" resumes it, "turn the lamp back on"."""
_BRING_BACK = re.compile(r"^(?:bring|get)\s+(?:back\s+(?P<before>.+)|(?P<after>.+?)\s+back)$")
"""Music wanted back: "bring the music back", "bring back the tunes" (a player's resume; a robot
brought back is a motion, and stays one)."""
_LEARNER_SWITCH = re.compile(
    r"^(?P<verb>open|close)\s+(?=(?:the|my|our|your|all|both|every|this|that|it|them)\b)"
)
"""A learner's "open the light" / "close the light" (on and off in many languages): the verb
first, a device after it; "close to the stairs" or "come close" are no switch."""
_REPLAY = re.compile(
    # "play it again", "play that song one more time", "start the song again": what is loaded,
    # again ("again" is a tag the speech layer has already peeled off).
    r"^(?:play|hear|(?:re)?start) (?:it|that|this|the|my)(?: (?:song|track|tune|one|music|playlist))?"
    r"(?: (?:again|(?:1 )?more time|once more|over))?$"
)
_REPEAT_OFF = re.compile(
    r"\b(?:repeat|loop)\w*\s+off\b|\b(?:turn|switch)\s+off\s+(?:the\s+)?(?:repeat|loop)\w*"
    r"|\bno (?:more )?(?:repeat|loop)\w*|\bun-?loop\w*|\bdisable (?:the )?(?:repeat|loop)\w*"
)
_REPEAT = re.compile(r"\b(?:repeat|loop)\w*\b|\bon (?:a )?loop\b|\bover and over\b")
_PLAY = re.compile(
    r"^(?:play|put on|queue up|throw on|blast|hear|listen to|have|get|give me|start|start playing|go with)"
    r"\s+(?P<query>.+)$"
)
_BY = re.compile(
    r"^(?:something|anything|some\s+(?:music|songs?|tunes?|tracks?)|a\s+(?:song|track|tune))\s+(?:by|from)\s+\S"
)
"""Music said by who made it, with no verb: "something by the Beatles" asks for it played."""
_SPLIT_PARTICLE = re.compile(
    r"^(put|throw|stick)\s+(something|anything|some\s+\w+(?:\s+\w+)?|a\s+(?:song|track|tune)|music)\s+on\b"
)
""""put something on by …": the particle after its object, said as "put on something by …"."""
_PLAY_VERBS = ("play", "put on", "queue", "throw on", "listen", "hear")
"""Verbs that play whatever follows; the others of :data:`_PLAY` ("have", "get") only a genre."""
_PLAYED_WORDS = re.compile(
    r"\b(?:music|songs?|tracks?|tunes?|stuff|playlist|radio|some|something|a bit of|a little)\b"
)
"""Words around a genre that name no device: "some jazz music", "a bit of classical stuff"."""
_LOOK_VERB = r"(?:look\w*|glanc\w*|peek\w*|peer\w*|gaz\w*|tilt\w*|turn\w*\s+(?:\w+\s+)?(?:head|eyes|face)|point\w*\s+(?:\w+\s+)?(?:head|eyes|face)|lift\w*\s+(?:\w+\s+)?(?:head|eyes|chin)|lower\w*\s+(?:\w+\s+)?(?:head|eyes|chin)|raise\w*\s+(?:\w+\s+)?(?:head|eyes|chin))"
_LOOK = re.compile(
    rf"\b{_LOOK_VERB}\b(?:\s+\w+){{0,4}}?\s+(?P<direction>left|right|up|down|upwards?|downwards?)\b"
)
"""The head turned or tilted one way: "look up", "glance over to your right", "tilt your head down",
"turn your head to the left", "eyes up"."""
_THING = (
    r"(?:at|toward|towards|to)\s+(?:the\s+|your\s+|my\s+)?"
    r"(?P<thing>ceiling|sky|roof|stars|lights?|floor|ground|feet|desk|table|lap|keyboard)\b"
)
_LOOK_AT = re.compile(rf"\b{_LOOK_VERB}\b(?:\s+\w+){{0,2}}?\s+{_THING}")
_AT_THING = re.compile(rf"\b{_THING}")
"""Looking at a thing that is up or down: "look up at the ceiling", "glance at the floor"."""
_ASIDE = re.compile(
    r"\b(?:over|to|at|towards?|your|the|its|his|her|side|a|little|bit|quick|quickly|briefly)\b"
)
"""Words around a look that name no device: "glance over to your right side"."""
_UPWARD = frozenset({"ceiling", "sky", "roof", "stars", "light", "lights"})
_HEAD_CHANGE = re.compile(r"\b(?:lift|raise)\w*\b|\b(?:lower|drop)\w*\b")
_LOOK_FRONT = re.compile(
    r"\blook\w*(?:\s+\w+){0,2}?\s+(?:straight(?:\s+ahead)?|ahead|forwards?|(?:to |at )?the front|front|"
    r"cent(?:er|re)|normal(?:ly)?)\b"
    r"|\b(?:reset|recent(?:er|re)|cent(?:er|re)|straighten)\w*\b(?:\s+\S+){0,3}?\s+head\b"
    r"|\bhead\s+(?:straight|forwards?|cent(?:er|re)d?)\b"
)
_FACE_FRONT = re.compile(
    r"\b(?:face|turn|rotate|spin|swivel|point|twist)\w*\b(?:\s+\S+){0,4}?\s+(?:back\s+)?(?:to\s+|towards?\s+)?"
    r"(?:the\s+)?(?:front|forwards?|ahead|straight(?:\s+ahead)?|cent(?:er|re)|middle)\b"
    r"(?!\s+(?!again\b|now\b|please\b|and\b|then\b|side\b|way\b|position\b)[a-z])"  # not "the front door"
    r"|\b(?:face|facing)\s+(?:forwards?|front|ahead|straight)\b"
)
"""Back to where the robot faces when it starts: "face forward again", "turn your body back to the
front". Only a driver with such a pose declares ``face_front``; for the others it is no action."""
_LEFT = re.compile(r"\b(?:left|counter-?clockwise|anti-?clockwise)\b")
_RIGHT = re.compile(r"\b(?:right|clockwise)\b")
_AROUND = re.compile(r"\b(?:around|round|about)\b")
_COUNTS = {"once": 1, "twice": 2, "2 times": 2, "3 times": 3, "thrice": 3}
_TIMES = re.compile(r"\b(?:once|twice|thrice|[23] times)\b")
_MOVE_VERB = re.compile(
    r"\b(?:drive|go|goes|move|walk|roll|scoot|step|head|come|advance|creep|inch|travel|trot|run|zoom|"
    r"nudge|shuffle|wheel|get|bring|take|back|reverse|retreat)\w*\b"
)
_BACKWARD = re.compile(r"\b(?:back(?:\s+\w+){0,3}?\s+up|backwards?|back|reverse|retreat|away from me)\b")
_BACK_WORDS = re.compile(r"\b(?:backwards?|back|reverse|retreat|away from me)\b")
"""What :data:`_BACKWARD` matched, less the words between "back" and "up": "back the dog up"."""
_FORWARD = re.compile(r"\b(?:forwards?|ahead|onwards?|closer|towards? me|straight)\b")


def read_action(clause: str, colours: frozenset[str], genres: frozenset[str] = frozenset()) -> Said | None:
    """The action ``clause`` asks for, or None when it names no action this lexicon knows.

    ``colours`` are the colour names the world's lights know; ``genres`` the kinds of music its
    players declare (a clause that names one wants it played: "I'd love some jazz")."""
    quantity = find_quantity(clause)
    text = clause.replace(quantity.text, " ", 1) if quantity else clause
    size = vague_size(text)
    plain = " ".join(remove_vague(text).split())
    if _UNDOCK.search(plain):
        return Said("undock", rest=_cut(plain, _UNDOCK, _MOVE_VERB))
    if _DOCK.search(plain):
        return Said("dock", rest=_cut(plain, _DOCK, _MOVE_VERB))
    if _SHUFFLE_OFF.search(plain):
        return Said("shuffle", {"flag": False}, _cut(plain, _SHUFFLE_OFF))
    if _SHUFFLE.search(plain):
        return Said("shuffle", {"flag": True}, _cut(plain, _SHUFFLE))
    if _PREVIOUS.search(plain):
        return Said("previous", rest=_cut(plain, _PREVIOUS))
    if _NEXT.search(plain):
        return Said("next", rest=_cut(plain, _NEXT, _PRESS))
    if _REPEAT_OFF.search(plain):
        return Said("repeat_off", rest=_cut(plain, _REPEAT_OFF, _TURN_VERB))
    if _REPEAT.search(plain):
        return Said("repeat", rest=_cut(plain, _REPEAT, re.compile(r"\b(?:put|set|turn|on)\b")))
    if _PAUSE.search(plain):
        return Said("pause", rest=_cut(plain, _PAUSE, _PRESS))
    back_on = _BACK_ON.search(plain)
    if back_on:
        return Said("switch_on", rest=back_on.group("what").strip())
    brought = _BRING_BACK.match(plain)
    if brought and re.search(r"\b(?:music|songs?|tunes?|tracks?|sound|audio|playlist|radio)\b", plain):
        return Said("resume", rest=(brought.group("before") or brought.group("after")).strip())
    learner = _LEARNER_SWITCH.match(plain)
    if learner:
        action = "switch_on" if learner.group("verb") == "open" else "switch_off"
        return Said(action, rest=plain[learner.end() :].strip())
    if _RESUME.search(plain) or _REPLAY.match(clause):
        return Said("resume", rest=_cut(plain, _RESUME, _PRESS))
    spoken = _SAY.match(_MODAL_WHO.sub(r"have \g<who> ", clause))
    if spoken:
        return Said("say", {"text": spoken.group("text")}, rest=spoken.group("who") or "")
    if _WAKE.search(plain):
        return Said("wake", rest=_cut(plain, _WAKE))
    if _SLEEP.search(plain):
        return Said("sleep", rest=_cut(plain, _SLEEP))
    clause = _SPLIT_PARTICLE.sub(r"\1 on \2", clause)
    if _BY.match(clause):
        clause = f"play {clause}"
    played = _PLAY.match(clause)
    if played and (clause.startswith(_PLAY_VERBS) or _genre(played.group("query"), genres)):
        query = re.sub(
            r"^(?:some|something|anything|a bit of|a little)\s+(?:by\s+|from\s+)?", "", played.group("query")
        )
        return Said("play", {"query": search_words(query)}, rest="")
    genre = _genre(plain, genres)
    if genre is not None and not _OFF.search(plain) and not _PAUSE.search(plain):
        # "some jazz in the living room", "how about some classical": a kind of music, wanted.
        rest = _cut(plain, re.compile(rf"\b{re.escape(genre)}\b"), _PLAYED_WORDS)
        return Said("play", {"query": genre}, rest=rest)
    if _LOOK_FRONT.search(plain):
        return Said("look", {"direction": "front"}, _cut(plain, _LOOK_FRONT))
    if _FACE_FRONT.search(plain) and not _LEFT.search(plain) and not _RIGHT.search(plain):
        front = re.compile(
            r"\b(?:face|facing|turn|rotate|spin|swivel|point|twist|back|to|towards?|front|forwards?|ahead|"
            r"straight|cent(?:er|re)|middle|body|base)\b"
        )
        if re.search(r"\bhead\b", plain):
            return Said("look", {"direction": "front"}, _cut(plain, front, re.compile(r"\bhead\b")))
        body = "body" if re.search(r"\b(?:body|base)\b", plain) else None  # the body only, not the head
        return Said("face_front", rest=_cut(plain, front), family=body)
    looked = _LOOK.search(plain)
    if looked:
        direction = looked.group("direction").removesuffix("s").removesuffix("wards").removesuffix("ward")
        return Said("look", {"direction": direction}, _cut(plain, _LOOK, _AT_THING, _ASIDE))
    looked_at = _LOOK_AT.search(plain)
    if looked_at:
        direction = "up" if looked_at.group("thing") in _UPWARD else "down"
        return Said("look", {"direction": direction}, _cut(plain, _LOOK_AT, _ASIDE))
    tilted = _HEAD_CHANGE.search(plain) if re.search(r"\b(?:head|chin|eyes)\b", plain) else None
    if tilted:
        direction = "up" if re.match(r"(?:lift|raise)", tilted.group(0)) else "down"
        return Said(
            "look",
            {"direction": direction},
            _cut(plain, _HEAD_CHANGE, _ASIDE, re.compile(r"\b(?:head|chin|eyes)\b")),
        )
    # A colour is never a motion: "switch the lamp back to warm white" goes back to a colour.
    said = (
        _colour(plain, colours)
        or _motion(plain, quantity, size)
        or _light_or_sound(plain, quantity, size, colours)
    )
    if said is not None and quantity is not None and not said.values:
        return None  # a number the action does not take: not this reader's to guess
    return replace(said, quantity=quantity) if said is not None and quantity is not None else said


def restate(clause: str, said: Said) -> str:
    """``clause`` with its number said the way a person would say it back.

    The reader works on digits (:func:`~.quantities.spell_numbers` made "three quarters" 0.75),
    so a reply built from the clause would say "set the lamp to 0.75". The value the action
    took is said instead, in its unit: "75%", "90°", "30 cm", "2.5 m", "2700 K".
    """
    if said.quantity is None:
        return clause
    for meaning in ("level", "change", "angle", "distance", "kelvin"):
        value = said.values.get(meaning)
        if isinstance(value, int | float) and not isinstance(value, bool):
            return clause.replace(said.quantity.text, _spoken(meaning, abs(float(value))), 1)
    return clause


def _spoken(meaning: str, value: float) -> str:
    if meaning in ("level", "change"):
        return f"{round(value)}%"
    if meaning == "angle":
        return f"{value:g}°"
    if meaning == "distance":
        return f"{round(value * 100)} cm" if value < 1 else f"{value:g} m"
    return f"{value:g} K"


def _motion(text: str, quantity: Quantity | None, size: Size) -> Said | None:
    angle_unit = quantity is not None and quantity.unit in ("degree", "turn")
    sideways = _LEFT.search(text) or _RIGHT.search(text) or _AROUND.search(text)
    distance_unit = quantity is not None and quantity.unit in METRES_PER
    turning = _TURN_VERB.search(text) or (_MOVE_VERB.search(text) and sideways and not distance_unit)
    if turning and (sideways or angle_unit) and not re.search(r"\b(?:on|off|up|down)\b", text):
        if quantity is not None and quantity.unit == "turn":
            degrees = quantity.value * 360
        elif quantity is not None and quantity.unit == "degree":
            degrees = quantity.value
        elif _AROUND.search(text) and not (_LEFT.search(text) or _RIGHT.search(text)):
            degrees = 180
        else:
            degrees = SIZES["angle"][size]
        sign = -1 if _RIGHT.search(text) and not _LEFT.search(text) else 1
        times = _TIMES.search(text)
        degrees *= _COUNTS[times.group(0)] if times else 1
        return Said(
            "turn",
            {"angle": sign * degrees},
            _cut(text, _TURN_VERB, _MOVE_VERB, _LEFT, _RIGHT, _AROUND, _TIMES),
        )
    backward = _BACKWARD.search(text)
    forward = _FORWARD.search(text)
    # A verb, or a direction with a distance ("turtlebot forward 1.5 metres"): never a bare "back".
    if (_MOVE_VERB.search(text) and (backward or forward or distance_unit)) or (
        distance_unit and (backward or forward)
    ):
        if quantity is not None and quantity.unit in METRES_PER:
            metres = quantity.value * METRES_PER[quantity.unit]
        else:
            metres = SIZES["distance"][size]
        sign = -1 if backward else 1
        particles = [_BACK_WORDS, re.compile(r"\bup\b")] if backward else []
        return Said("move", {"distance": sign * metres}, _cut(text, *particles, _FORWARD, _MOVE_VERB))
    return None


def _genre(text: str, genres: frozenset[str]) -> str | None:
    """The one kind of music ``text`` names, if any ("jazz" in "some jazz please")."""
    found = [genre for genre in genres if re.search(rf"\b{re.escape(genre)}\b", text)]
    return max(found, key=len) if found else None
