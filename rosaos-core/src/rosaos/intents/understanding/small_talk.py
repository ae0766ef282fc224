"""Small talk: a greeting, thanks or a goodbye, answered in one short line with nothing moved.

A sentence is small talk only when every part of it is: a greeting ("hi", "good morning"), a
how-are-you, thanks or praise ("thanks so much, that's perfect"), a goodbye, and the name it is
said to ("hey Reachy"). Anything else in it (a command, a question about state) makes it not small
talk, so "thanks, now turn off the lamp" is still read as a command by the command reader.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Literal

SmallTalk = Literal["greeting", "thanks", "goodbye"]

_GREETING = (
    r"hi|hello|hey|hiya|howdy|yo|greetings|good (?:morning|afternoon|evening|day)|morning|evening"
    r"|nice to (?:see|meet) you|(?:it's )?good to see you"
)
_HOW_ARE_YOU = (
    r"how(?:'s| is| are)? (?:it going|are you|you doing|are you doing|are things|things|is everything|"
    r"is your day(?: going)?|have you been)(?: today| this morning| tonight)?"
    r"|what's up|whats up|how do you do|you (?:ok|okay|alright|good)"
)
_THANKS = (
    r"thanks?(?: you)?(?: so much| very much| a lot| a bunch| a million)?|thank you|cheers|ta|much appreciated"
    r"|(?:that's|that is|that was|it's|it was|you're|you are|you've been|you were) (?:so |really |very |super |just )*"
    r"(?:perfect|great|lovely|awesome|amazing|brilliant|wonderful|helpful|nice|fantastic|excellent|good|a star|the best)"
    r"|(?:perfect|great|lovely|awesome|brilliant|wonderful|nice|excellent|good job|well done|nice one)"
    r"|(?:really |very |super )?helpful"
)
_GOODBYE = (
    r"bye|goodbye|bye bye|bye for now|see you(?: later| soon| tomorrow| around)?|see ya|good night|goodnight"
    r"|take care|have a (?:good|nice|great) (?:day|night|evening|one)|later|catch you later|talk (?:to you )?(?:later|soon)"
)
_FILLER = r"oh|ok|okay|well|so|and|again|there|everyone|everybody|buddy|friend|pal|mate|today|too|for (?:that|everything|the help|your help)"
_PARTS: tuple[tuple[SmallTalk | None, re.Pattern[str]], ...] = (
    ("greeting", re.compile(rf"^(?:{_GREETING})(?: (?:{_GREETING}))*$")),
    ("greeting", re.compile(rf"^(?:{_HOW_ARE_YOU})$")),
    ("thanks", re.compile(rf"^(?:{_THANKS})(?: (?:{_FILLER}))*$")),
    ("goodbye", re.compile(rf"^(?:{_GOODBYE})$")),
    (None, re.compile(rf"^(?:{_FILLER})$")),
)
_ADDRESS = frozenset({"there", "rosa", "robot", "robots", "everyone", "buddy"})
_REPLIES: dict[SmallTalk, str] = {
    "greeting": "Hi! I'm doing well, thanks. What can I do for you?",
    "thanks": "You're welcome!",
    "goodbye": "Bye for now!",
}


def read_small_talk(text: str, is_name: Callable[[str], bool]) -> SmallTalk | None:
    """What kind of small talk ``text`` is, or None when any part of it is something else.

    ``is_name`` says whether a word names one of this world's devices: "hey Reachy" is said to it.
    A part may end in such a name (or "there", "robot"), never in any other word."""
    said = text.lower().replace("’", "'")
    parts = [part.strip() for part in re.split(r"[,.!?;:]+|\s+-\s+", said) if part.strip()]
    kinds: list[SmallTalk] = []
    for part in parts:
        part = " ".join(part.split())
        if part in _ADDRESS or is_name(part):
            continue
        kind = _part_kind(part, is_name)
        if kind is False:
            return None
        if kind is not None:
            kinds.append(kind)
    return kinds[0] if kinds else None


def _part_kind(part: str, is_name: Callable[[str], bool]) -> SmallTalk | Literal[False] | None:
    """The kind of one part, said to whoever its names name ("thank you Reachy"); False: not small talk."""
    words = [word for word in part.split() if word not in _ADDRESS and not is_name(word)]
    for candidate in dict.fromkeys((part, " ".join(words))):
        for kind, form in _PARTS:
            if candidate and form.match(candidate):
                return kind
    return False


def small_talk_reply(kind: SmallTalk) -> str:
    """The one-line answer to small talk of ``kind``."""
    return _REPLIES[kind]
