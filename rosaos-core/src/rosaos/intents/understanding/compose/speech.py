"""The command inside what people say: one mechanism for fillers, politeness and speech acts.

People wrap a command in discourse: interjections ("oh man", "ugh", "okay so"), request frames
("could ya", "would you be a dear and", "I'd like you to"), and tags ("real quick", "for me",
"please", "will you?"). None of them changes what is asked, so :func:`command_words` peels them
off both ends of a sentence (and of each clause), repeatedly, by their *role* in the sentence,
never by which command they wrap. :func:`clauses` then cuts the sentence at "and", "then" and
commas. What stays is never guessed at: negations and questions are recognised
(:func:`negated`, :func:`asks`) so the reader leaves them to the rest of the engine.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from rosaos.intents.understanding.compose.places import name_places
from rosaos.intents.understanding.compose.quantities import spell_numbers

_INTERJECTIONS = (
    "oh man", "oh boy", "oh dear", "oh my god", "oh my", "oh no", "oh", "ah", "aah", "uh", "uhh", "um",
    "umm", "er", "erm", "hmm", "hm", "ugh", "argh", "meh", "ok", "okay", "okey", "alright", "all right",
    "right", "hey there", "hey", "hi", "hello", "yo", "so", "well", "now", "listen", "man", "dude", "mate",
    "buddy", "gosh", "geez", "jeez", "damn", "wow", "sorry", "excuse me", "yes", "yeah", "yep", "also",
    "and", "then", "actually", "honestly", "quick", "quickly", "real quick", "just", "kindly",
    "please", "pretty please", "hey assistant", "computer", "oops", "whoops", "anyway", "anyways",
    "maybe", "perhaps", "possibly", "kinda", "i guess", "i think", "i suppose", "by any chance",
    "whoa", "woah", "wait", "hmm okay", "so yeah", "you know what", "right so",
)  # fmt: skip
_REQUEST_FRAMES = (
    r"(?:can|could|would|will|wouldja|couldja|can't|won't)\s+(?:you|ya|u|yah)(?:\s+please)?",
    r"(?:do|would)\s+you\s+mind(?:\s+if\s+you)?",
    r"(?:be\s+a\s+(?:dear|darling|love|pal|sweetheart)|do\s+me\s+a\s+(?:favou?r|solid))(?:\s+and)?",
    # "would you be so kind as to", "be kind enough to": politeness with its own verb
    r"(?:(?:can|could|would|will)\s+(?:you|ya)\s+)?(?:please\s+)?be\s+(?:so\s+kind\s+as|kind\s+enough|good\s+enough)\s+to",
    r"i(?:'d|\s+would)\s+(?:really\s+)?appreciate\s+it\s+if\s+you(?:'d|\s+would|\s+could)?",
    r"go\s+ahead\s+and",
    r"(?:i|we)\s+(?:could|can)\s+(?:really\s+)?(?:do\s+with|use)",
    r"(?:i'm|im|i\s+am|we're|we\s+are)\s+in\s+the\s+mood\s+for",
    r"(?:i|we)\s+(?:fancy|feel\s+like)(?:\s+hearing)?",
    r"you\s+(?:can|could|may|might\s+as\s+well|should)(?:\s+(?:now|just|please))?(?:\s+go\s+ahead\s+and)?",
    r"i(?:'d|\s+would)\s+(?:like|love)(?:\s+you|\s+it\s+if\s+you)?(?:\s+to)?",
    r"i\s+(?:want|need)\s+you\s+to",
    # "please you say hello": a learner's "you" before the imperative, not a subject of a remark
    r"you(?=\s+(?:say|tell|announce|look|turn|switch|put|play|make|set|dim|go|move|come|give|show|shout|"
    r"nod|shake|wake|dance|greet|walk|drive|dock)\b)",
    r"i\s+(?:want|wanna)(?:\s+to)?(?=\s+(?:turn|switch|set|make|hear|listen))",
    r"(?:how|what)\s+about(?:\s+you)?",
    r"let's",
    r"time\s+to",
    r"try\s+(?:to|and)",
    r"if\s+you\s+(?:can|could|would)",
    r"for\s+me",
    r"and",
)
_TAGS = (
    "please", "pretty please", "for me", "for us", "real quick", "really quick", "quick", "quickly",
    "right now", "now", "asap", "thanks", "thank you", "thx", "ta", "cheers", "will you", "would you",
    "could you", "can you", "won't you", "will ya", "would ya", "could ya", "can ya", "ok", "okay",
    "if you can", "if you could", "if you don't mind", "when you get a chance", "when you can", "yeah",
    "mate", "buddy", "dude", "man", "then", "already", "again", "as well", "too",
    "thanks a lot", "thanks so much", "thank you so much", "thank you very much", "thanks very much",
    "much appreciated", "would you kindly", "k", "pls", "plz",
    "for a sec", "for a second", "for a moment", "for a bit", "a sec", "by any chance", "if possible",
    "if that's ok", "if that's okay", "if that's alright", "when you have a moment", "do you know",
    "you know", "i think", "i guess", "maybe", "perhaps", "at the moment", "currently", "still",
    "right away", "straight away", "for now",
)  # fmt: skip


def _alternatives(words: tuple[str, ...]) -> str:
    return "|".join(re.escape(word) for word in sorted(words, key=len, reverse=True))


_LEAD = re.compile(
    rf"^(?:(?:{_alternatives(_INTERJECTIONS)})\b|(?:{'|'.join(_REQUEST_FRAMES)})(?=\s|$))[\s,!.?;:-]*",
    re.IGNORECASE,
)
# A term of address, set off by a comma ("…, dear", "love, …"): who is spoken to, not what is
# asked. The comma is what tells "for me, love" from "play something I love".
_ADDRESS = (
    r"(?:my\s+)?(?:dear|dearest|love|darling|honey|hon|sweetie|sweetheart|babe|pet|pal|friend|buddy|"
    r"mate|sir|madam|ma'am|chief|boss)"
)
_TAIL = re.compile(
    rf"[\s,!.?;:-]*\b(?:{_alternatives(_TAGS)})[\s,!.?;:-]*$|\s*,\s*{_ADDRESS}[\s,!.?;:-]*$", re.IGNORECASE
)
_LEAD_ADDRESS = re.compile(rf"^{_ADDRESS}\s*,\s*", re.IGNORECASE)
_SPLIT = re.compile(
    r"\s*(?:[,;]\s*(?:and\s+then|and|then|after\s+that|plus|also)?|\band\s+then\b|\bthen\b|\band\b"
    r"|\bafter\s+that\b|\bafterwards\b|\bplus\b)\s*",
    re.IGNORECASE,
)
_NEGATION = re.compile(
    # "I don't like this one, skip it": a feeling about what plays, the reason for a command.
    # "not this one, skip it": a rejection of what plays, the reason for the command after it.
    r"\b(?:(?:don't|dont|do not)(?!\s+(?:really\s+)?(?:like|love|enjoy|care for|dig)\b)|never|no need to|"
    r"not(?!\s+(?:this|that)(?:\s+(?:one|song|track|tune))?\s*(?:,|$))|won't|shouldn't|mustn't|didn't|doesn't|nothing|"
    r"no more|forget it|never mind|nevermind|cancel)\b",
    re.IGNORECASE,
)
_QUESTION = re.compile(
    r"^(?:is|are|was|were|what|what's|whats|how|where|who|why|when|which|does|has|am|should|shall|"
    r"isn't|aren't|(?:do|did|have)\s+(?:you|i|we|they|it|any))\b"
    # an indirect question: "tell me whether the light is off", "I wonder if the robot docked"
    r"|^(?:tell\s+me|let\s+me\s+know|i\s+wonder|i'm\s+wondering|any\s+idea|check|know)\s+"
    r"(?:if|whether|what|which|where|how|who|when)\b|\bwhether\b",
    re.IGNORECASE,
)
_SUBJECT = (
    r"(?:i|i'm|im|i've|i'll|i'd|we|we're|we've|we'll|you're|he|he's|she|she's|they|they're|it|it's|its|"
    r"there|there's|that's|everyone|everyone's|everybody|everybody's|someone|somebody|nobody|no one|"
    r"people|guests|(?:the|my|our|his|her|their|a)\s+\w+(?:'s)?)"
)
_OCCASION = re.compile(r"^(?:it's\s+|its\s+)?(?:about\s+)?time\s+(?:to|for)\s+[\w'-]+$")
""""time to work", "time for bed": one word after "time to" is an occasion or a verb to read
whole, not a request frame to strip ("time to turn on the lamp" is one)."""
_IS = re.compile(r"^((?:the|my|our|his|her|their|a)\s+(?:\w+\s+)?\w+)'s\b")
"""A subject with "'s" for "is": "the baby's asleep" is "the baby is asleep"."""
_REASON = re.compile(
    rf"\s+(?:because|cause|'cause|cuz|coz|cos|since|as|so that|so|now that|while|given that|seeing as|where|from where)"
    rf"\s+{_SUBJECT}(?=\s|$).*$",
    re.IGNORECASE,
)
_REMARK = re.compile(
    rf"^(?:{_SUBJECT}\s+(?:\w+\s+)?(?:is|are|was|were|am|has|have|had|will|can't|cannot|won't|isn't|aren't|"
    r"keeps?|just|got|gets?|hates?|(?:\w+ing))\b"
    r"|(?:i'm|im|i've|i'll(?!\s+(?:have|take)\b)|(?:i'd|we'd)(?!\s+(?:like|love|prefer|rather|want)\b)|we're|we've|we'll|you're|he's|she's|they're|it's|there's|that's|everyone's|"
    r"everybody's|someone's|somebody's|nobody's|no one's|everything's|nothing's|something's)\b"
    r"|(?:the|my|our|his|her|their|a)\s+(?:\w+\s+){0,2}\w+\s+(?:hurts?|aches?|sleeps|naps|works|starts|feels|looks|"
    r"seems|sounds|smells|came|went|left|arrived|woke|fell|says|said|called|rang|knocked|is|are|was|were)\b"
    r"|(?:this|that|these|those)\s+(?:is|are|was|were)\b"
    r"|(?:thank you|thanks|much appreciated|appreciate it|cheers|love you|you're the best|good job|well done)\b"
    # a remark to the robot addressed: "you look tired", "you've been good", "you were great today"
    r"|you\s+(?:(?:look|seem|sound)\s+(?!(?:to|at|left|right|up|down|around|over|behind|for)\b)|were\b|did\s+(?:a\s+|so\s+)?(?:great|good|well|fine)\b)"
    r"|you've\s+been\b"
    # a need before or after the command: "I need proper light for chopping", "I need to focus"
    r"|(?:i|we)\s+(?:really\s+|just\s+)?(?:need|want)\s+(?:to\s+(?!turn|switch|set|make|put|play|have|hear)\w+"
    r"|(?!(?:\w+\s+){0,3}(?:on|off)\b)(?:\w+\s+){1,3}(?:for|to)\b)"
    # a rejection of what plays, the reason for the command beside it: "not this one, skip it"
    r"|(?:nah\s+|no\s+)?not\s+(?:this|that)(?:\s+(?:one|song|track|tune))?(?:\s+again)?$"
    r"|(?:i|we|they|he|she)\s+(?!want\b|need\b|would\b|wanna\b|gotta\b)\w+)",
    re.IGNORECASE,
)
_STOP = re.compile(
    r"\b(?:stop|halt|freeze|hold it|enough(?!\s+(?:to|for|as)\b)|abort|emergency)\b", re.IGNORECASE
)


_HEDGE = re.compile(
    r"(,|\bto|\bat)\s+(?:like|say|about|around|roughly|approximately|something\s+like|maybe|more\s+or\s+less)\s+"
    r"(\d+(?:\.\d+)?(?:\s*(?:%|percent\b)|(?=\s*(?:,|$))))"
)
"""A hedged number after "to", "at" or a comma ("like 30 percent", "to about 40"): the number."""
_NOT_TOO = re.compile(
    r"\bnot\s+(?:too|so|very|overly)\s+(bright|loud)(?:ly)?\b(?:\s*,?\s*(\d+(?:\.\d+)?\s*(?:%|percent)))?"
)
_MODERATE = {"bright": "dimmer", "loud": "quieter"}
""""not too bright" is a request for a moderate level, not a negation: dimmer, unless a
number follows ("not too bright, 30 percent": the number)."""


_THERE = re.compile(
    r"^(?P<verb>look|glance|peek|turn|face|point)(?P<how>\s+(?:your\s+)?(?:head|eyes|face))?\s+(?:at|to|towards?)\s+"
    r"(?:the|that|this|my|our)\s+[\w' -]+?\s*,\s*(?:it's|it\s+is|its|they're|they\s+are|he's|she's)\s+"
    r"(?:(?:just|right|over)\s+)?(?:on|to|at)\s+(?:your|the)\s+(?P<side>left|right)(?:\s+(?:hand\s+)?side)?$"
)
"""A thing to look at and where it is said after it ("look at the window, it's on your left"):
the direction is where to look."""


def _moderate(found: re.Match[str]) -> str:
    return found.group(2) or _MODERATE[found.group(1)]


def normalise(text: str) -> str:
    """Lowercase, plain apostrophes, number words as digits, rooms by their own word ("where we
    cook": the kitchen, before "where" can be read as the start of a reason), no end punctuation."""
    text = text.lower().replace("\u2019", "'").replace("\u2018", "'")
    text = re.sub(r"[!?.]+\s+(?=\S)", ", ", text)  # one sentence, then another: two clauses
    text = re.sub(r"[\"“”!?.]+(?=\s|$)", " ", text)
    text = re.sub(r"\s+", " ", text).strip()
    text = re.sub(r"\brise and shine\b", "wake up", text)  # an idiom: its "and" joins no two commands
    text = re.sub(r"\bnice and (?=(?:bright|loud|dim|low|quiet|soft)\b)", "nice ", text)  # one level
    text = _HEDGE.sub(r"\1 \2", spell_numbers(text))
    text = _THERE.sub(r"\g<verb>\g<how> to your \g<side>", text)
    return name_places(_NOT_TOO.sub(_moderate, text))


_DEVICE = r"(?P<device>(?:my|the|our|this|that)\s+(?:\w+\s+){0,3}?\w+)"
_WISHES = (
    # "I want my lamp to be purple", "we'd like the speaker to be at 30": the wish is the command
    re.compile(
        r"^(?:(?:i|we)\s+(?:really\s+)?(?:want|wanna|need)|(?:i|we)(?:'d|\s+would)\s+(?:really\s+)?(?:like|love|prefer))\s+"
        rf"{_DEVICE}\s+to\s+be\s+(?P<state>.+)$"
    ),
    # "can we have the lamp at 40 percent", "could I get the lamp a bit warmer"
    re.compile(
        rf"^(?:can|could|may)\s+(?:we|i)\s+(?:have|get)\s+{_DEVICE}\s+"
        r"(?P<state>(?:at|to|on|off)\b.*|.*\b(?:\d+\s*(?:%|percent)|brighter|dimmer|louder|quieter|warmer|cooler)$)"
    ),
)


@dataclass(frozen=True)
class Wish:
    """A wish for a device's state ("I want my lamp to be purple") and the command it asks for."""

    command: str
    device: str
    state: str


def _wish(text: str) -> Wish | None:
    """A wish for a device's state as the command it asks for: "make the lamp purple", "set the
    lamp to 40 percent". Only a device phrase and a state; "I'd like some jazz" is no wish."""
    for wish in _WISHES:
        found = wish.match(text)
        if found is not None:
            device, state = found.group("device"), found.group("state")
            level = re.match(r"^(?:at|to)\s+(.+)$", state)
            command = f"set {device} to {level.group(1)}" if level else f"make {device} {state}"
            return Wish(command, device, level.group(1) if level else state)
    return None


def wished(text: str) -> Wish | None:
    """The wish ``text`` says, if it says one, before any template reads it as something else
    ("I want the lamp to be plaid" once turned the lamp on at 100 %)."""
    plain = text.lower().replace("\u2019", "'").strip(" .!?")
    previous = None
    while previous != plain:
        previous = plain
        plain = _TAIL.sub("", plain).strip()
        wish = _wish(plain)  # before "I'd like" is stripped as a request frame
        if wish is not None:
            return wish
        plain = _LEAD_ADDRESS.sub("", _LEAD.sub("", plain)).strip()
    return None


def command_words(text: str) -> str:
    """``text`` without the discourse around its command, at both ends, as often as it is there;
    a wish for a state said as the command (:func:`_wish`)."""
    previous = None
    while previous != text:
        previous = text
        wish = _wish(text)  # before "I'd like" is stripped as a request frame
        text = wish.command if wish is not None else text
        text = _LEAD_ADDRESS.sub("", _LEAD.sub("", text)).strip()
        text = _TAIL.sub("", text).strip()
    return text


def clauses(text: str) -> list[str]:
    """``text`` cut into clauses at commas, "and", "then"; each without its own discourse, and
    without the reason given for it ("…, because it's too bright": :func:`without_reason`)."""
    pieces = _SPLIT.split(without_reason(command_words(text)))
    return [piece if _OCCASION.match(piece) or remark(piece) else command_words(piece) for piece in pieces]


def without_reason(text: str) -> str:
    """``text`` without a reason clause after its command: "dim it because it's late", "put the
    lamp on so I can read". A subordinator followed by a subject starts a clause that says why;
    what it says changes nothing of what is asked."""
    for found in _REASON.finditer(text):
        if re.search(r"\bas\s+\w+$", text[: found.start()]) and found.group(0).lstrip().startswith("as "):
            continue  # "as warm as it goes": a comparison, not a reason
        return text[: found.start()].strip()
    return text.strip()


def remark(clause: str) -> bool:
    """Whether ``clause`` states something rather than asks for it: a subject and its verb ("the
    baby is napping", "I'm heading out", "we have guests", "it's too close to the stairs").
    Said beside a command, it is the reason for it and dropped; alone, it may be a need
    (the reader's :meth:`~rosaos.intents.understanding.compose.reader.Composer` reads those)."""
    return _REMARK.match(clause) is not None or _REMARK.match(_IS.sub(r"\1 is", clause)) is not None


def negated(text: str) -> bool:
    """Whether ``text`` says not to do something ("don't", "never", "no need to")."""
    return _NEGATION.search(text) is not None


def negated_command(text: str) -> bool:
    """Whether a command of ``text`` is negated: :func:`negated` on its clauses, without the
    remarks said after the first clause ("skip this one, I'm not in the mood": the "not" is the
    reason's, not the command's). A remark that opens the sentence still counts: "I'm not sure,
    turn it off" is not read as a plain command."""
    pieces = clauses(text)
    kept = [piece for index, piece in enumerate(pieces) if index == 0 or not remark(piece)]
    return negated(", ".join(kept))


def asks(text: str) -> bool:
    """Whether ``text`` is a question about state ("is the lamp on?"), not a request."""
    return _QUESTION.match(command_words(text)) is not None


def says_stop(text: str) -> bool:
    """Whether ``text`` says stop: another part of the engine owns that, never this reader."""
    return _STOP.search(text) is not None
