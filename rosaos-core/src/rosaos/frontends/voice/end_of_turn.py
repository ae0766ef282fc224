"""End of turn by meaning: is what the user said so far a whole command?

A fixed pause of ``silence_seconds`` (0.55 s) ends every utterance, and most of it is spent after
the sentence is already complete: people answer each other after about 200 ms. So the pipeline
asks a :class:`TurnJudge` about each draft transcript (see :mod:`rosaos.frontends.voice.early`):

- a whole command the offline engine would run as it stands ("turn on the kitchen light") ends
  the turn after ``complete_silence_seconds`` (0.18 s) of silence;
- anything else ("turn on the …", "set the volume to", a question back, nothing understood)
  waits the full ``silence_seconds``, as before.

The judge is the offline engine itself, reached through the kernel's ``POST /understand`` (the
kernel already holds the engine for its world; the voice process stays small). Only the end of
the turn moves: what is sent is the final utterance, never a draft, so nothing (and no robot)
starts to move on a guess.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol

from rosaos.frontends.voice.wake import is_noise, strip_wake_phrase
from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable


class TurnJudge(Protocol):
    """Says whether a command, as heard so far, is whole."""

    async def complete(self, command: str) -> bool: ...


class KernelJudge:
    """The offline engine of the running kernel, asked over ``POST /understand``.

    A kernel that cannot answer (too old, restarting) makes every draft "not complete": the turn
    then ends on the full pause, as it did before this existed.
    """

    def __init__(self, client: KernelClient) -> None:
        self.client = client

    async def complete(self, command: str) -> bool:
        try:
            answer = await self.client.request("POST", "/understand", json={"text": command})
        except KernelUnavailable:
            return False
        return bool(answer.get("complete")) if isinstance(answer, dict) else False


class EngineJudge:
    """An engine in this process: ``exact(text)`` is true when it would act on ``text`` as it stands.

    For tools and tests that hold an :class:`~rosaos.intents.understanding.matching.IntentMatcher`
    (``lambda text: matcher.match(text).is_exact``).
    """

    def __init__(self, exact: Callable[[str], bool]) -> None:
        self.exact = exact

    async def complete(self, command: str) -> bool:
        return self.exact(command)


def command_of(transcript: str, wake_phrases: Sequence[str]) -> str:
    """The command in a draft transcript: what follows the wake phrase, if it leads."""
    rest = strip_wake_phrase(transcript, wake_phrases)
    return (rest if rest is not None else transcript).strip()


async def is_whole_command(judge: TurnJudge, transcript: str, wake_phrases: Sequence[str]) -> bool:
    """Whether ``transcript`` (a draft) holds a whole command: the turn may end after a short pause."""
    command = command_of(transcript, wake_phrases)
    if is_noise(command):
        return False
    return await judge.complete(command)
