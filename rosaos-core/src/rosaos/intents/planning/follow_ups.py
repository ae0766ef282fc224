"""Follow-ups in the offline engine: "X, then Y", "X, and when you find someone, Y", "X; if you see …, Y".

One sentence becomes one process for X whose plan carries Y as :class:`~rosaos.events.plan.FollowUp`.
Nothing holds Y's devices while X runs: the kernel launches Y when X's callback arrives, and only
when X succeeded. The follow-up travels in X's plan, a field of X's job and of its
``worker_callback`` event, so it survives a kernel restart (the event store has it).

- Planning (:func:`plan_follow_up`): split the sentence at "then" or at a condition ("when",
  "once", "as soon as", "if", "after"); X and Y must each match exactly, X as one process.
  A condition about finding ("find", "see", "spot", "detect") makes Y wait for a step of X that
  returns ``found: true`` (the ROS ``search`` tool's result); "then" or "when you are done" only
  needs X to succeed. Y may itself carry a follow-up ("X, then Y, then Z").
- In the process (:func:`unmet_output`): when X's results do not satisfy the condition, its
  output is the plan's ``unmet`` sentence ("I did not find anyone, so I did not turn the lamp green.").
- In the kernel (:func:`callback_response`): on X's callback, launch Y if X ended ``ok`` and its
  output is not the ``unmet`` sentence; else tell the user Y was not done, and why.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from pydantic_ai.messages import ModelResponsePart, TextPart, ToolCallPart

from rosaos.events.callback import WorkerCallback
from rosaos.events.plan import FollowUp, FollowUpLaunch, Plan, launch_args, result_data
from rosaos.intents.understanding.match_result import MatchResult, ProcessPlan

# Where a follow-up starts: "…, then Y", "… and then Y"; "…, and when/once/if … Y".
_THEN = re.compile(r"(?:\s*[,;]\s*|\s+)(?:and\s+)?(?:then|after that|afterwards)\s*,?\s+", re.IGNORECASE)
_CONDITION = re.compile(
    r"(?:\s*[,;]\s*|\s+)(?:and\s+)?(?:when(?:ever)?|once|as soon as|if|after)\s+", re.IGNORECASE
)
_FINDING = re.compile(
    r"\b(?:find|finds|found|see|sees|seen|saw|spot|spots|spotted|detect|detects|detected|there(?:'s| is| are))\b",
    re.IGNORECASE,
)
FOUND_KEY = "found"


@dataclass(frozen=True)
class FollowUpSplit:
    """A sentence read as "first, (condition), then": the parts as the user said them."""

    first: str
    condition: str | None
    then: str


def candidate_splits(text: str, is_command: Callable[[str], bool]) -> list[FollowUpSplit]:
    """Every way to read ``text`` as a follow-up, best first; ``is_command`` tells a full command."""
    splits: list[FollowUpSplit] = []
    for marker in _THEN.finditer(text):
        first, then = text[: marker.start()], text[marker.end() :]
        if first.strip() and then.strip():
            splits.append(FollowUpSplit(first.strip(), None, then.strip()))
    for marker in _CONDITION.finditer(text):
        first, rest = text[: marker.start()].strip(), text[marker.end() :].strip()
        if not first or not rest:
            continue
        condition, _, then = rest.partition(",")
        if then.strip():
            splits.append(FollowUpSplit(first, condition.strip(), then.strip()))
            continue
        # No comma ("when you find someone turn the lamp green"): the action is the longest tail
        # that is a command on its own.
        words = rest.split()
        for cut in range(1, len(words)):
            tail = " ".join(words[cut:])
            if is_command(tail):
                splits.append(FollowUpSplit(first, " ".join(words[:cut]), tail))
                break
    return splits


def plan_follow_up(
    text: str,
    match: Callable[[str], MatchResult],
    language: str = "en",
    literal: Callable[[str], MatchResult] | None = None,
) -> MatchResult | None:
    """The processes for a follow-up sentence (one process for X carrying Y), or None if it is not one.

    ``literal`` reads a part exactly as said (no everyday rephrasing, no close guess): where no
    comma ends the condition, it finds where the action starts, so "someone turn off the light"
    is not taken for the action of "when you find someone turn off the light".
    """
    text = " ".join(text.split())
    strict = literal or match
    for split in candidate_splits(text, lambda part: strict(part).is_exact):
        first = match(split.first)
        if not first.is_exact or len(first.processes) != 1:
            continue
        then = plan_follow_up(split.then, match, language, literal) or match(split.then)
        if not then.is_exact:
            continue
        summary = " and ".join(_clause(process.summary) for process in then.processes)
        when = {FOUND_KEY: True} if split.condition and _FINDING.search(split.condition) else None
        follow_up = FollowUp(
            launches=[
                FollowUpLaunch(devices=list(p.devices), summary=p.summary, plan=p.plan)
                for p in then.processes
            ],
            summary=summary,
            when=when,
            unmet=_unmet(summary, language) if when else "",
        )
        process = first.processes[0]
        plan = process.plan.model_copy(
            update={"then": follow_up, "ack": f"{process.plan.ack} {_ack_then(split, summary)}".strip()}
        )
        return MatchResult("plans", text, processes=(ProcessPlan(process.devices, process.summary, plan),))
    return None


def unmet_output(plan: Plan, results: Sequence[Any]) -> str | None:
    """The process's output when its follow-up's condition does not hold on ``results``, else None.

    ``results`` are the plan's step results in order; the newest one that has every ``when`` key
    decides. None of them having the keys counts as "not met": never launch on a guess.
    """
    if plan.then is None or not plan.then.when:
        return None
    keys = plan.then.when
    for result in reversed(results):
        value = result_data(result)
        if isinstance(value, dict) and all(key in value for key in keys):
            return None if all(value[key] == expected for key, expected in keys.items()) else plan.then.unmet
    return plan.then.unmet


def callback_response(
    callback: WorkerCallback, launch: str | None, failure_reply: str
) -> list[ModelResponsePart] | None:
    """The kernel's response to the callback of a process with a follow-up; None when it has none.

    ``failure_reply`` is what the kernel would say about a failed callback without a follow-up.
    """
    plan = callback.plan
    if plan is None or plan.then is None:
        return None
    follow_up = plan.then
    output = (callback.output or "").strip()
    if callback.status != "ok":
        said = failure_reply.strip()
        said += "" if said.endswith((".", "!", "?")) else "."
        return [TextPart(f"{said} So I did not {follow_up.summary}.")]
    if follow_up.unmet and output == follow_up.unmet:
        return [TextPart(output)]
    if launch is None:
        return [TextPart(f"{output} I could not {follow_up.summary}: no launch_process tool.")]
    return [
        ToolCallPart(launch, launch_args(item.summary, item.devices, item.plan))
        for item in follow_up.launches
    ]


def _clause(summary: str) -> str:
    """A process summary as a clause: "Turn the lamp green." → "turn the lamp green"."""
    first = summary.split(". This process:", 1)[0].strip().rstrip(".?!")
    return first[:1].lower() + first[1:]


def _ack_then(split: FollowUpSplit, summary: str) -> str:
    if split.condition:
        return f"When {_you(split.condition)}, I'll {summary}."
    return f"Then I'll {summary}."


def _you(condition: str) -> str:
    """The user's condition, as the kernel says it back ("you find someone" → "I find someone")."""
    return re.sub(r"\byou\b", "I", condition.strip().rstrip(",").strip(), flags=re.IGNORECASE)


def _unmet(summary: str, language: str) -> str:
    # English only for now; the kernel compares this exact sentence, so it is fixed at planning.
    return f"I did not find anyone, so I did not {summary}."
