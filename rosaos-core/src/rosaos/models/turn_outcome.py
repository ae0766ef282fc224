"""The typed outcome of a kernel turn (:data:`rosaos.events.reply_outcome.TurnOutcome`), from its messages.

The offline engine knows why it launched nothing (not understood, refused, a question asked), so it
marks its final text with it (:func:`marked`), in the part's ``provider_details`` under the
``rosaos`` provider: data for programs, never sent to an LLM provider, never read from the words.
An LLM's words are not read at all: its turn is ``refused`` only where that is certain, when it
called tools and every call was refused or failed (an unknown device, a held one). Anything else
is ``done``.
"""

from __future__ import annotations

from collections.abc import Sequence

from pydantic_ai.messages import ModelMessage, ModelResponse, TextPart

from rosaos.events.reply_outcome import TurnOutcome, as_outcome
from rosaos.intents.understanding.match_result import MatchResult
from rosaos.models.conversation import tool_outcomes

PROVIDER = "rosaos"
OUTCOME_KEY = "outcome"


def marked(text: str, outcome: TurnOutcome) -> TextPart:
    """A reply that carries why nothing was done (or that it was)."""
    return TextPart(text, provider_name=PROVIDER, provider_details={OUTCOME_KEY: outcome})


def unmatched(result: MatchResult) -> TurnOutcome:
    """The outcome of answering a sentence the engine did not run (``result`` is not exact)."""
    if result.kind == "clarify":
        return "needs_confirmation" if result.suggestion else "needs_answer"
    return "refused" if result.refusal else "not_understood"


def turn_outcome(messages: Sequence[ModelMessage]) -> TurnOutcome:
    """How the turn made of ``messages`` (one run's new messages) ended for what was asked."""
    for message in reversed(messages):
        if isinstance(message, ModelResponse):
            for part in message.parts:
                if isinstance(part, TextPart) and part.provider_name == PROVIDER:
                    outcome = as_outcome((part.provider_details or {}).get(OUTCOME_KEY))
                    if outcome is not None:
                        return outcome
            break  # only the final response says how the turn ended
    outcomes = tool_outcomes(messages)
    if outcomes and not any(outcome.ok for outcome in outcomes):
        return "refused"
    return "done"
