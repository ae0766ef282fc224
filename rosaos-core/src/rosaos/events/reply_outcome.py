"""How a kernel turn ended for what the user asked: the ``outcome`` of each ``kernel_reply``.

Typed, so a client never reads it back out of the reply's words (issue 26): the offline engine
marks it where it decides (:mod:`rosaos.models.turn_outcome`), the kernel loop reads it from the
turn's messages and publishes it in the reply's data, and ``rosaos chat --wait`` maps it to its
exit code (:mod:`rosaos.frontends.chat`).
"""

from __future__ import annotations

from typing import Literal, get_args

TurnOutcome = Literal["done", "refused", "not_understood", "needs_answer", "needs_confirmation"]
"""- ``done``: acted on, or answered (a question, "what can you do?", chit-chat a reply answers);
  whether the processes it launched succeed is told by their callbacks, not here.
- ``refused``: understood, and nothing was done: a device, colour, value or place this world has
  not, or every tool call of the turn was refused or failed (a held device, an unknown device).
- ``not_understood``: the sentence was not understood; nothing was done.
- ``needs_answer``: nothing was done yet: the kernel asked a question ("which one do you mean?").
- ``needs_confirmation``: nothing was done yet: "Did you mean …?" waits for a yes.
"""

TURN_OUTCOMES: tuple[TurnOutcome, ...] = get_args(TurnOutcome)


def as_outcome(value: object) -> TurnOutcome | None:
    """``value`` (from an update's JSON data) as an outcome; None when absent or unknown (a kernel
    older or newer than this client)."""
    return next((outcome for outcome in TURN_OUTCOMES if outcome == value), None)
