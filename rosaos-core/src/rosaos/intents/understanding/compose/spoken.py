"""Speech as typed: hesitations inside a command, a setting said after the music, reported speech.

:func:`tidy` runs once on every sentence, before any reading, and rewrites three families of
everyday phrasing into the plain command the rest of the engine reads. None of them knows a
command or a device:

- **Hesitations and self-repairs anywhere in a clause.** Fillers such as "um", "uh", "erm" are
  never words of a command; "like", "you know", "I mean" are not when set off by commas ("play,
  like, some jazz"); "kind of"/"sort of" before a gradable word hedge it ("kind of low", never the album "Kind of Blue"); a
  function word said twice is a restart ("turn the, um, the lamp off"). Words to be *said* ("say
  um, hello") are the user's own and are kept as they are.
- **A setting said after the music**: "play X at volume 25", "put on some jazz, volume 30",
  "play X loud": the search gets the music words only, and the volume is a step of its own.
- **Reported speech to someone**: "tell the dog I love it" is words to say to the dog, in the
  second person ("I love you"); "say I love you to the doggy" says "I love you". The one told
  is the audience, never a device to command.
"""

from __future__ import annotations

import re

from rosaos.intents.understanding.compose.corrections import comparatives, corrected

_SPEECH_VERB = re.compile(
    r"\b(?:say|says|tell|announce|speak|repeat|shout|whisper|read\s+out)\b", re.IGNORECASE
)
"""Where words to be said may start: hesitations after it are the user's own words."""
_HESITATION = re.compile(r"(?:,\s*)?\b(?:u+m+|u+h+|uhm+|e+r+m*|ehm|hmm+)\b(?:\s*,)?", re.IGNORECASE)
"""Sounds that are never words of a command, with the commas that set them off."""
_ASIDE = re.compile(
    r",\s*(?:like|you\s+know|i\s+mean|kinda|sorta|kind\s+of|sort\s+of|basically|literally|well|so)\s*,",
    re.IGNORECASE,
)
"""A filler set off by commas on both sides ("play, like, some jazz")."""
_HEDGE = re.compile(
    r"\b(?:kind\s+of|sort\s+of|kinda|sorta)\s+(?=(?:really\s+|very\s+)?(?:low|high|dim|dimmer|bright|brighter|"
    r"loud|louder|quiet|quieter|soft|softer|warm|warmer|cool|cooler|cold|dark|darker|slow|slowly|fast|quick|"
    r"quickly|soft|softly|gently|red|blue|green|yellow|orange|purple|pink|white)\b)",
)
"""A hedge before a gradable or colour word: "kind of low" is low; "Kind of Blue" is a title (case kept)."""
_EXPLETIVE = re.compile(
    r"\b(?:damn|darn|dang|goddamn|freaking|frigging|frickin[g']?|flipping|bloody|blasted|effing|fucking|"
    r"stupid|silly|dumb)\s+(?=[a-z])",
    re.IGNORECASE,
)
"""A word of feeling before what it is said of ("the stupid lamp", "the damn music"): never which one."""
_VAGUE_TAIL = re.compile(
    r"\s+or\s+(?:something|whatever|anything)(?:\s+like\s+(?:that|it))?\b", re.IGNORECASE
)
""""jazz or something": the thing asked for, not a choice between two."""
_LIKE = re.compile(
    r"\b(play|put\s+on|throw\s+on|turn|switch|set|make|dim|give\s+me)\s+like\s+(?=(?:some|a|an|the|my|it)\b)",
    re.IGNORECASE,
)
""""play like some jazz": "like" between a verb and its object is a filler, "something like jazz" is not."""
_RESTARTED = (
    "the", "a", "an", "my", "our", "your", "this", "that", "these", "those", "it", "its", "to", "on", "off",
    "in", "at", "up", "down", "turn", "switch", "set", "make", "play", "put", "can", "could", "you",
    "please", "and", "of", "with", "for",
)  # fmt: skip
_REPEAT = re.compile(rf"\b({'|'.join(_RESTARTED)})(?:\s*,\s*|\s+)\1\b", re.IGNORECASE)
"""A function word or command verb said twice, a restart: "turn off the, the lamp"."""

_PLAY = r"\b(?:play|put|throw|stick|queue\s+up|blast|start\s+playing)\b"
_TENS = r"(?:twenty|thirty|forty|fifty|sixty|seventy|eighty|ninety)"
_UNITS = (
    r"(?:zero|one|two|three|four|five|six|seven|eight|nine|ten|eleven|twelve|thirteen|fourteen|fifteen|"
    r"sixteen|seventeen|eighteen|nineteen|(?:a|one)\s+hundred)"
)
_NUMBER = rf"(?P<n>\d+(?:\.\d+)?|{_TENS}(?:[ -](?:one|two|three|four|five|six|seven|eight|nine))?|{_UNITS})"
_SETTING = re.compile(
    rf"^(?P<music>.*{_PLAY}.+?)(?:\s*,\s*|\s+)(?:"
    rf"(?:(?:at|with|on)\s+)?(?:(?:a|the)\s+)?volume\s+(?:(?:at|to|of|on)\s+)?{_NUMBER}(?:\s*%|\s+percent)?"
    rf"|(?:at|with)\s+{_NUMBER.replace('?P<n>', '?P<m>')}(?:\s*%|\s+percent)?\s+(?:volume|loudness)"
    rf"|(?:at|with)\s+(?:(?:a|the)\s+)?(?P<level>full|max|maximum|top|high|low|quiet|soft|medium)\s+volume"
    rf"|(?P<how>(?:(?:really|very|pretty|nice\s+and|super|not\s+too|not\s+so)\s+)?"
    rf"(?:loud|loudly|quiet|quietly|soft|softly|gently))"
    rf")(?:[\s,]+(?:please|thanks|thank\s+you|for\s+me))?[\s,.!?]*$",
    re.IGNORECASE,
)
"""Music, then how loud: "play X at volume 25", "put on jazz, volume 30", "play X loud"."""
_LEVELS = {
    "full": 100, "max": 100, "maximum": 100, "top": 100, "high": 80, "medium": 35,
    "low": 25, "quiet": 25, "soft": 25,
    "loud": 80, "loudly": 80, "quietly": 25, "softly": 25, "gently": 25,
}  # fmt: skip
"""Volume for a word of loudness said with the music: loud is well above the usual half."""

_TELL = re.compile(
    r"^(?P<lead>.*?\b)tell\s+(?P<who>(?:the|my|our|your)\s+(?:[\w'-]+\s+)??[\w'-]+)\s+(?:that\s+)?"
    r"(?P<words>(?:i|i'm|im|i've|i'd|we|we're|you|you're|it|it's|its|he|he's|she|she's|they|they're|"
    r"good|well|nice|thanks|thank|happy|hello|hi|goodnight|good\s+night)\b.*)$",
    re.IGNORECASE,
)
"""Words told to someone: "tell the dog (that) I love it", "tell my robot it's a good boy"."""
_BEINGS = r"(?:dog|doggy|doggie|doggo|puppy|pup|robot|bot|cat|kitty|reachy|turtlebot|turtle|puppypi)"
"""Who words may be said *to* and not be part of them: a pet or a robot ("say good night to
everyone" is words for everyone, said as written)."""
_SAY_TO = re.compile(
    rf"^(?P<say>.*?\bsay\s+(?!to\b).+?)\s+to\s+(?:(?:the|my|our|your)\s+)?(?:[\w'-]+\s+)?{_BEINGS}(?:[\s,]+(?:please|now|for\s+me))?[\s,.!?]*$",
    re.IGNORECASE,
)
"""Words, then who they are for: "say I love you to the doggy"."""
_SECOND_PERSON = [
    (re.compile(r"\b(?:it|he|she)\s+is\b", re.IGNORECASE), "you are"),
    (re.compile(r"\b(?:it|he|she)\s+was\b", re.IGNORECASE), "you were"),
    (re.compile(r"\b(?:it|he|she)\s+has\b", re.IGNORECASE), "you have"),
    (
        re.compile(
            r"\b(?:it's|he's|she's)\b(?!\s+(?:time|late|early|getting|raining|cold|hot)\b)", re.IGNORECASE
        ),
        "you're",
    ),
    (re.compile(r"\b(?:itself|himself|herself)\b", re.IGNORECASE), "yourself"),
    (re.compile(r"\b(?:its|his)\b", re.IGNORECASE), "your"),
    (re.compile(r"\bher(?=\s+(?!so\b|very\b|too\b|a\s+lot\b|lots\b|much\b)[a-z])", re.IGNORECASE), "your"),
    (re.compile(r"\b(?:it|him|her|he|she)\b(?!')", re.IGNORECASE), "you"),
]
"""The one told, said of in the third person, becomes "you": "tell the dog it's a good boy"."""


def tidy(text: str) -> str:
    """``text`` with hesitations dropped, a trailing volume made a step of its own, and reported
    speech said directly (see the module docstring). Unchanged when none of them is there."""
    text = _reported(comparatives(corrected(text)))  # "30, I mean 40"; "make more quiet"
    speech = _SPEECH_VERB.search(text)
    head, said = (text[: speech.end()], text[speech.end() :]) if speech else (text, "")
    head = _without_hesitations(head)
    return _setting(f"{head}{said}") if not speech else f"{head}{said}"


def _without_hesitations(text: str) -> str:
    previous = None
    while previous != text:
        previous = text
        text = _HESITATION.sub(" ", text)
        text = _ASIDE.sub(" ", text)
        text = _HEDGE.sub("", text)
        text = _EXPLETIVE.sub("", text)
        text = _VAGUE_TAIL.sub("", text)
        text = _LIKE.sub(r"\1 ", text)
        text = _REPEAT.sub(r"\1", text)
    text = re.sub(r"\s+([,.!?])", r"\1", text)
    text = re.sub(r"^[\s,]+|(?<=\s),\s*", "", text)
    return " ".join(text.split())


def _setting(text: str) -> str:
    found = _SETTING.match(text)
    if found is None:
        return text
    number = found.group("n") or found.group("m")
    if found.group("how") and re.search(r"\b(?:something|anything|stuff)$", found.group("music")):
        return text  # "play something quiet": what to play, not how loud
    word = (found.group("level") or found.group("how") or "").lower().split()
    if word[:2] == ["not", "too"] or word[:2] == ["not", "so"]:
        word = ["medium"]  # "not too loud": below the usual half, never loud
    level = number if number is not None else str(_LEVELS.get(word[-1], 0)) if word else None
    if level is None or level == "0":
        return text
    return f"{found.group('music').rstrip(' ,')} and set the volume to {level} percent"


def _reported(text: str) -> str:
    told = _TELL.match(text)
    if told is not None:
        words = told.group("words")
        if not told.group("who").lower().endswith("s"):  # one told, not "the kids"
            for pattern, direct in _SECOND_PERSON:
                words = pattern.sub(direct, words)
        return f"{told.group('lead')}say {words}"
    to = _SAY_TO.match(text)
    return to.group("say") if to is not None else text
