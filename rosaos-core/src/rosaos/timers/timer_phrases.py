"""What a sentence asks of the timers: set one, list them, or cancel one (English).

"turn off the light in ten minutes", "in 1.5 hours, stop the music", "stop the music at 11 pm",
"at half past seven turn on the lamp", "set a timer for 20 minutes to turn off the fan",
"what timers are set?", "cancel that timer", "cancel the light timer", "cancel timer 3".
Numbers come in digits or words. The action is checked by the caller against the intent
templates (:mod:`rosaos.timers.timer_turn`): a timer is only set for a command the engine
understands now. Clock times are local and resolved by the kernel (:mod:`rosaos.timers.timer_text`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import datetime, timedelta

_ONES = ["zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten", "eleven",
         "twelve", "thirteen", "fourteen", "fifteen", "sixteen", "seventeen", "eighteen", "nineteen"]  # fmt: skip
_TENS = {
    "twenty": 20,
    "thirty": 30,
    "forty": 40,
    "fifty": 50,
    "sixty": 60,
    "seventy": 70,
    "eighty": 80,
    "ninety": 90,
}
SMALL_NUMBERS = {word: value for value, word in enumerate(_ONES)}
UNIT_SECONDS = {
    **dict.fromkeys(["s", "sec", "secs", "second", "seconds"], 1.0),
    **dict.fromkeys(["m", "min", "mins", "minute", "minutes"], 60.0),
    **dict.fromkeys(["h", "hr", "hrs", "hour", "hours"], 3600.0),
    **dict.fromkeys(["day", "days"], 86400.0),
}
_PM_MARKERS = (
    "pm",
    "in the afternoon",
    "in the evening",
    "this afternoon",
    "this evening",
    "tonight",
    "at night",
)
_AM_MARKERS = ("am", "in the morning", "this morning")
# Not "alarm": "is the alarm on?" is a question for a security device, not about timers.
_TIMER_WORD = r"\b(?:timers?|reminders?)\b"
_LIST = re.compile(
    rf"^(?:what|which|any|are|is|list|show|tell|how|do|give|check)\b.*{_TIMER_WORD}|^{_TIMER_WORD}$"
)
_CANCEL = re.compile(
    rf"^(?:cancel|delete|remove|stop|clear|forget|abort|drop|kill|turn off)\b.*{_TIMER_WORD}"
)
_CANCEL_FILLER = frozenset(
    [
        "cancel",
        "delete",
        "remove",
        "stop",
        "clear",
        "forget",
        "abort",
        "drop",
        "kill",
        "turn",
        "off",
        "the",
        "that",
        "this",
        "my",
        "last",
        "one",
        "it",
        "please",
        "timer",
        "timers",
        "alarm",
        "alarms",
        "reminder",
        "reminders",
        "for",
        "to",
        "a",
        "an",
        "of",
        "which",
        "i",
        "set",
        "you",
        "just",
    ]
)
_SET_PREFIX = re.compile(
    r"^(?:please )?(?:set|start|make) (?:a |an |me a )?(?:timer|alarm|reminder)(?: for)?\s*"
)
_SPOKEN = re.compile(
    r"\b(?:say|announce|tell\s+(?!me\b)\w+|let\s+\w+\s+know|shout|call\s+out|inform\s+\w+)\s+(?:that\s+)?\w"
)
"""A verb of speech and its content: a time in the content is what is said, not when to say it."""
_TOKEN = re.compile(r"\d+(?:\.\d+)?|[a-z]+")


@dataclass(frozen=True)
class SetTimer:
    """Do ``action`` after ``in_seconds``, or at local clock time ``at`` (``HH:MM`` or ISO 8601)."""

    action: str
    in_seconds: float | None = None
    at: str | None = None
    weak: bool = False
    """Read from a bare hour ("at 11"): also a plausible setting ("set the volume at 11"), so a
    sentence that is a complete command as a whole stays a command."""


@dataclass(frozen=True)
class ListTimers:
    """ "What timers are set?"."""


@dataclass(frozen=True)
class CancelTimer:
    """Cancel one timer by id, the ones whose action has these words, all, or (none given) the newest."""

    timer_id: int | None = None
    matching: str | None = None
    cancel_all: bool = False


TimerRequest = SetTimer | ListTimers | CancelTimer


def normalize(text: str) -> str:
    """Lower case, no trailing punctuation, ``p.m.`` → ``pm``, one space between words."""
    text = text.lower().strip().rstrip("?.!").replace("o'clock", "oclock").replace("’", "'")
    text = re.sub(r"\b([ap])\.\s?m\b\.?", r"\1m", text)
    text = re.sub(r"(\d)\s*([ap]m)\b", r"\1 \2", text)
    return " ".join(text.replace(",", " , ").split()).removeprefix("please ").removesuffix(" please")


def read_timer_request(text: str, now: datetime) -> TimerRequest | None:
    """The timer request in ``text``, or None when it is not about timers. ``now``: aware, local."""
    said = normalize(text)
    if _CANCEL.search(said):
        return _cancel(said)
    if _LIST.search(said) and not _SET_PREFIX.match(said):
        return ListTimers()
    return _set(said, now)


def _cancel(said: str) -> CancelTimer:
    words = _TOKEN.findall(said)
    if "all" in words or "every" in words or "everything" in words:
        return CancelTimer(cancel_all=True)
    number = re.search(rf"{_TIMER_WORD}\s+(?:number\s+|#\s*)?(\d+|[a-z]+)\b", said)
    if number is not None:
        value = _number_value(number.group(1))
        if value is not None and value == int(value) and value >= 1:
            return CancelTimer(timer_id=int(value))
    rest = [word for word in words if word not in _CANCEL_FILLER]
    return CancelTimer(matching=" ".join(rest) or None)


def _set(said: str, now: datetime) -> SetTimer | None:
    prefixed = _SET_PREFIX.match(said)
    if prefixed:  # "set a timer for 20 minutes to turn off the fan"
        rest = said[prefixed.end() :]
        for cut in _cuts(rest):
            head, tail = rest[:cut].strip(" ,"), rest[cut:].strip(" ,")
            seconds = parse_duration(head)
            if seconds is not None:
                return SetTimer(
                    action=_action(tail.removeprefix("to ").removeprefix("and ")), in_seconds=seconds
                )
        return None
    # "turn off the light in ten minutes" / "stop the music at 11 pm": the time comes last.
    # Not inside words to say: "announce that the meeting starts in five minutes" says them now.
    spoken = _SPOKEN.search(said)
    for marker in (" tomorrow at ", " in ", " after ", " at "):
        start = said.rfind(marker)
        while start > 0 and (spoken is None or start < spoken.start()):
            found = _timing(said[start + 1 :], now)
            if found is not None:
                return SetTimer(_action(said[:start]), found.in_seconds, found.at, found.weak)
            start = said.rfind(marker, 0, start)
    # "in ten minutes, turn off the light" / "at 7 am turn on the lamp": the time comes first.
    if said.split(" ", 1)[0] in ("in", "after", "at", "tomorrow"):
        for cut in reversed(_cuts(said)):
            found = _timing(said[:cut].strip(" ,"), now)
            if found is not None:
                action = _action(said[cut:].strip(" ,").removeprefix("then "))
                return SetTimer(action, found.in_seconds, found.at, found.weak)
    return None


def _cuts(text: str) -> list[int]:
    """Every word boundary of ``text``."""
    return [match.start() for match in re.finditer(r" ", text)]


def _action(text: str) -> str:
    return text.strip(" ,").removesuffix(" ,").strip()


def _timing(phrase: str, now: datetime) -> SetTimer | None:
    """``in ten minutes`` → in_seconds 600; ``at 11 pm`` → at ``23:00``; else None (no action yet)."""
    words = phrase.split()
    if not words:
        return None
    if words[0] in ("in", "after"):
        rest = " ".join(words[1:]).removesuffix(" from now").removesuffix(" time")
        seconds = parse_duration(rest)
        return None if seconds is None else SetTimer("", in_seconds=seconds)
    tomorrow = words[0] == "tomorrow"
    if tomorrow:
        words = words[1:]
        if not words:
            return None
    if words[0] == "at":
        clock = parse_clock(" ".join(words[1:]), now)
        if clock is None:
            return None
        hhmm, weak = clock
        if not tomorrow:
            return SetTimer("", at=hhmm, weak=weak)
        hour, minute = map(int, hhmm.split(":"))
        day = (now.astimezone() + timedelta(days=1)).date()
        return SetTimer(
            "", at=datetime(day.year, day.month, day.day, hour, minute).isoformat(timespec="minutes")
        )
    return None


def parse_duration(text: str) -> float | None:
    """Seconds in ``ten minutes``, ``1.5 hours``, ``an hour and a half``, ``2 h 30 min``; else None."""
    tokens = _TOKEN.findall(text.lower().replace("-", " "))
    total, index, found = 0.0, 0, False
    while index < len(tokens):
        if (
            tokens[index] in ("and", "a", "an")
            and index + 1 < len(tokens)
            and tokens[index + 1]
            in (
                "half",
                "quarter",
            )
        ):
            index += 1
        if tokens[index] == "and" and found:
            index += 1
            continue
        if tokens[index] in ("half", "quarter"):
            value = 0.5 if tokens[index] == "half" else 0.25
            index += 1
            while index < len(tokens) and tokens[index] in ("of", "a", "an"):
                index += 1
        else:
            number = _read_number(tokens, index)
            if number is None:
                return None
            value, index = number
            if tokens[index : index + 3] == ["and", "a", "half"]:  # "two and a half hours"
                value, index = value + 0.5, index + 3
        if index >= len(tokens) or tokens[index] not in UNIT_SECONDS:
            return None
        unit = UNIT_SECONDS[tokens[index]]
        index += 1
        if tokens[index : index + 3] == ["and", "a", "half"]:  # "an hour and a half"
            value, index = value + 0.5, index + 3
        total, found = total + value * unit, True
    return total if found and total > 0 else None


def _read_number(tokens: list[str], index: int) -> tuple[float, int] | None:
    """A number at ``tokens[index]`` (digits, words, "a", "a couple of") and the index after it."""
    if index >= len(tokens):
        return None
    word = tokens[index]
    if word in ("a", "an") and tokens[index + 1 : index + 3] == ["couple", "of"]:
        return 2.0, index + 3
    if word in ("a", "an"):
        return 1.0, index + 1
    if word in _TENS:
        tens = _TENS[word]
        if (
            index + 1 < len(tokens)
            and tokens[index + 1] in SMALL_NUMBERS
            and 0 < SMALL_NUMBERS[tokens[index + 1]] < 10
        ):
            return float(tens + SMALL_NUMBERS[tokens[index + 1]]), index + 2
        return float(tens), index + 1
    value = _number_value(word)
    return None if value is None else (value, index + 1)


def _number_value(word: str) -> float | None:
    if re.fullmatch(r"\d+(?:\.\d+)?", word):
        return float(word)
    if word in SMALL_NUMBERS:
        return float(SMALL_NUMBERS[word])
    return float(_TENS[word]) if word in _TENS else None


def parse_clock(text: str, now: datetime) -> tuple[str, bool] | None:
    """``11 pm`` → ``("23:00", False)``; a bare ``11`` → the sooner of 11:00 and 23:00, weak."""
    text = f" {text.strip()} "
    meridiem = None
    stripped = True
    while stripped:  # "11 pm tonight": both markers go
        stripped = False
        for marker in _PM_MARKERS + _AM_MARKERS:
            if text.endswith(f" {marker} ") and text.strip() != marker:
                meridiem = "pm" if marker in _PM_MARKERS else "am"
                text, stripped = text[: -len(marker) - 1], True
    words = text.replace("oclock", " oclock ").split()
    marked = meridiem is not None or "oclock" in words
    words = [word for word in words if word != "oclock"]
    named = {"noon": (12, 0), "midday": (12, 0), "midnight": (0, 0)}
    if len(words) == 1 and words[0] in named:
        hour, minute = named[words[0]]
        return f"{hour:02d}:{minute:02d}", False
    parsed = _clock_words(words)
    if parsed is None:
        return None
    hour, minute, explicit = parsed
    if hour > 23 or minute > 59:
        return None
    # A bare number ("at 11", "at 20") may be a setting ("set the volume at 20"), not a time.
    weak = not marked and not explicit and len(words) == 1 and ":" not in words[0]
    if meridiem is not None:
        if hour > 12:
            return None
        hour = hour % 12 + (12 if meridiem == "pm" else 0)
        return f"{hour:02d}:{minute:02d}", False
    if explicit or hour == 0 or hour > 12:  # "23:00", "07:30": a 24-hour time
        return f"{hour:02d}:{minute:02d}", weak
    # "at 7" / "at seven thirty": the sooner of morning and evening.
    local = now.astimezone()
    candidates = []
    for candidate in (hour % 12, hour % 12 + 12):
        moment = local.replace(hour=candidate, minute=minute, second=0, microsecond=0)
        candidates.append((moment if moment > local else moment + timedelta(days=1), candidate))
    best = min(candidates)[1]
    return f"{best:02d}:{minute:02d}", weak


def _clock_words(words: list[str]) -> tuple[int, int, bool] | None:
    """(hour, minute, written as 24-hour HH:MM) from the words of a clock time, or None."""
    if not words:
        return None
    if len(words) == 1 and (found := re.fullmatch(r"(\d{1,2})[:.h](\d{2})", words[0])):
        return int(found[1]), int(found[2]), len(found[1]) == 2 and words[0][2] in ":h"
    if len(words) == 1 and (found := re.fullmatch(r"(\d{1,2})h", words[0])):
        return int(found[1]), 0, True
    # "half past seven", "quarter to eight", "ten past six", "twenty five to nine"
    for link in ("past", "to"):
        if link in words:
            at = words.index(link)
            minutes_words = [w for w in words[:at] if w not in ("a", "minutes", "minute")]
            minutes = {"half": 30, "quarter": 15}.get(" ".join(minutes_words))
            if minutes is None:
                number = _read_number(minutes_words, 0) if minutes_words else None
                if number is None or number[1] != len(minutes_words):
                    return None
                minutes = int(number[0])
            hour = _whole(words[at + 1 :])
            if hour is None or not 0 < minutes < 60:
                return None
            return (hour, minutes, False) if link == "past" else ((hour - 1) % 24, 60 - minutes, False)
    hour_number = _read_number(words, 0)
    if hour_number is None or words[0] in ("a", "an"):
        return None
    hour, index = int(hour_number[0]), hour_number[1]
    if hour_number[0] != hour:
        return None
    if index == len(words):
        return hour, 0, False
    if words[index] == "o" and index + 1 < len(words):  # "seven o five"
        index += 1
    minute = _whole(words[index:])
    return None if minute is None else (hour, minute, False)


def _whole(words: list[str]) -> int | None:
    number = _read_number(words, 0) if words else None
    if number is None or number[1] != len(words) or number[0] != int(number[0]):
        return None
    return int(number[0])


def duration_text(seconds: float) -> str:
    """``45 seconds``, ``10 minutes``, ``2 h 5 min``, ``3 days 4 h``: coarse, for speech."""
    seconds = round(abs(seconds))
    if seconds < 60:
        return f"{seconds} second{'s' if seconds != 1 else ''}"
    minutes = round(seconds / 60)
    if minutes < 60:
        return f"{minutes} minute{'s' if minutes != 1 else ''}"
    hours, minutes = divmod(minutes, 60)
    if hours < 24:
        return f"{hours} h {minutes} min" if minutes else f"{hours} hour{'s' if hours != 1 else ''}"
    days, hours = divmod(hours, 24)
    return f"{days} day{'s' if days != 1 else ''}" + (f" {hours} h" if hours else "")
