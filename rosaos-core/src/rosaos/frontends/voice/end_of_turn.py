"""End of turn by meaning: is what the user said so far a whole command?

A fixed pause of ``silence_seconds`` (0.55 s) ends every utterance, and most of it is spent after
the sentence is already complete: people answer each other after about 200 ms. So the pipeline
asks a :class:`TurnJudge` about each draft transcript (see :mod:`rosaos.frontends.voice.early`):

- a whole command the offline engine would run as it stands ("turn on the kitchen light") ends
  the turn after ``complete_silence_seconds`` (0.18 s) of silence, unless it would set a robot
  moving (``moves`` of ``POST /understand``): "drive the turtlebot forward" is whole, and "... one
  meter" may be on its way, so a motion always waits the full pause;
- anything else ("turn on the …", "set the volume to", a question back, nothing understood)
  waits the full ``silence_seconds``, as before. A draft whose last word cannot end an English
  sentence (an article, a possessive, a conjunction, a preposition that needs its object: see
  :data:`OPEN_ENDINGS`), or that stops partway into one of the world's names ("switch off the
  living …" of "living room lamp"), is never whole, whatever the engine makes of it: in a world
  with one light, "turn on the" already names it, but the speaker is plainly still talking.

The judge is the offline engine itself, reached through the kernel's ``POST /understand`` (the
kernel already holds the engine for its world; the voice process stays small). Only the end of
the turn moves: what is sent is the final utterance, never a draft, so nothing (and no robot)
starts to move on a guess.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol

from rosaos.frontends.voice.wake import is_noise, normalize, strip_wake_phrase
from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable

OPEN_ENDINGS = frozenset(
    {
        *("the", "a", "an", "some", "every", "each"),
        *("my", "your", "our", "their", "its"),
        *("and", "or", "but", "if", "when", "while", "until", "because"),
        *("to", "of", "at", "with", "into", "onto", "from", "for", "toward", "towards"),
        *("than", "about", "between", "through", "via"),
    }
)
"""Words a command does not end on: what follows them is still to come. Particles that can end one
("turn it on", "turn the music up", "lights off") are not here, nor pronouns ("play this")."""


class TurnJudge(Protocol):
    """Says whether a command, as heard so far, is whole."""

    names: Sequence[str]
    """The world's names of more than one word (devices, rooms, titles): a draft that ends inside
    one ("play Clair de …", "switch off the living …") is not whole."""

    async def complete(self, command: str) -> bool: ...


class KernelJudge:
    """The offline engine of the running kernel, asked over ``POST /understand``.

    A kernel that cannot answer (too old, restarting) makes every draft "not complete": the turn
    then ends on the full pause, as it did before this existed.
    """

    def __init__(self, client: KernelClient, names: Sequence[str] = ()) -> None:
        self.client = client
        self.names = names

    async def complete(self, command: str) -> bool:
        try:
            answer = await self.client.request("POST", "/understand", json={"text": command})
        except KernelUnavailable:
            return False
        if not isinstance(answer, dict):
            return False
        # A motion is never started on a guess about where the sentence ends: "drive the turtlebot
        # forward" is whole, and "... one meter" may be on its way.
        return bool(answer.get("complete")) and not answer.get("moves")


class EngineJudge:
    """An engine in this process: ``exact(text)`` is true when it would act on ``text`` as it stands
    (and, as :class:`KernelJudge` does, start no motion).

    For tools and tests that hold an :class:`~rosaos.intents.understanding.matching.IntentMatcher`
    (``lambda text: matcher.match(text).is_exact``).
    """

    def __init__(self, exact: Callable[[str], bool], names: Sequence[str] = ()) -> None:
        self.exact = exact
        self.names = names

    async def complete(self, command: str) -> bool:
        return self.exact(command)


def command_of(transcript: str, wake_phrases: Sequence[str]) -> str:
    """The command in a draft transcript: what follows the wake phrase, if it leads."""
    rest = strip_wake_phrase(transcript, wake_phrases)
    return (rest if rest is not None else transcript).strip()


async def is_whole_command(judge: TurnJudge, transcript: str, wake_phrases: Sequence[str]) -> bool:
    """Whether ``transcript`` (a draft) holds a whole command: the turn may end after a short pause."""
    command = command_of(transcript, wake_phrases)
    if is_noise(command) or ends_openly(command, judge.names):
        return False
    return await judge.complete(command)


def ends_openly(command: str, names: Sequence[str] = ()) -> bool:
    """``command`` stops where a sentence cannot end: on an open word ("turn on the", "set the volume
    to"), or partway into one of ``names`` ("play Clair de", "switch off the living")."""
    words = normalize(command).split()
    if not words:
        return False
    if words[-1] in OPEN_ENDINGS:
        return True
    for name in names:
        parts = normalize(name).split()
        for size in range(1, len(parts)):  # the last ``size`` words begin the name, and it goes on
            if words[-size:] == parts[:size]:
                return True
    return False
