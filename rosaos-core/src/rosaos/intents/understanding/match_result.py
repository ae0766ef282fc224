"""What a sentence means, as the kernel acts on it: :class:`MatchResult` and its :class:`ProcessPlan`s.

Built from the chosen readings of a sentence's clauses (:mod:`rosaos.intents.understanding.readings`): any
question or refusal wins and nothing is launched; otherwise one process per device, its tool
calls from every clause in order, with the replies the process and the kernel will say.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

from rosaos.events.plan import Plan, PlanStep, launch_args
from rosaos.intents.grammar.phrases import join_options, phrase
from rosaos.intents.understanding.readings import Reading, ReadingContext, readout_reply

MatchKind = Literal["plans", "clarify", "no_match"]


@dataclass(frozen=True)
class ProcessPlan:
    """One process to launch: the devices it needs, a readable summary and the plan."""

    devices: tuple[str, ...]
    summary: str
    plan: Plan

    @property
    def launch_args(self) -> dict[str, Any]:
        """The ``launch_process`` arguments: the summary as the task, the devices, the plan."""
        return launch_args(self.summary, self.devices, self.plan)


@dataclass(frozen=True)
class MatchResult:
    """What a sentence means: processes to launch, or a reply instead."""

    kind: MatchKind
    text: str
    processes: tuple[ProcessPlan, ...] = ()
    reply: str = ""
    """The clarifying question, refusal or "not understood" text (kinds other than ``plans``)."""
    suggestion: str = ""
    """For "Did you mean …?": the exact command a "yes" confirms."""
    refusal: bool = False
    """A ``no_match`` that refuses what it understood (a bad number, a negation): never guessed at."""

    @property
    def is_exact(self) -> bool:
        """True when the sentence matched completely and can run without asking anything."""
        return self.kind == "plans"

    def starts_motion(self, halts: Callable[[str], Sequence[str]]) -> bool:
        """Whether running it would set a robot moving: a step on a device that halts ``motion``
        (``halts(device)`` is its driver's ``DriverSpec.halts``) other than stopping it."""
        return any(
            "motion" in halts(step.device) and not step.tool.endswith("stop")
            for process in self.processes
            for step in process.plan.steps
        )


def build_result(context: ReadingContext, text: str, readings: list[Reading], picked: bool) -> MatchResult:
    """The result of ``text`` read as ``readings`` (one per clause).

    ``picked``: the targets were narrowed by the user's answer to "which one?", so replies name
    the device ("turn off the light (kitchen light)").
    """
    issues = list(dict.fromkeys(reading.issue for reading in readings if reading.issue))
    if issues:
        return MatchResult("clarify", text, reply=" ".join(issues))
    processes: dict[str, list[tuple[Reading, list[PlanStep]]]] = {}
    for reading in readings:
        for device, steps in reading.calls.items():
            processes.setdefault(device, []).append((reading, steps))
    plans = tuple(_process(context, device, parts, picked) for device, parts in processes.items())
    return MatchResult("plans", text, processes=plans)


def no_match(context: ReadingContext, text: str) -> MatchResult:
    """ "Not understood", listing the devices there are."""
    names = [device.display_name for device in context.devices.values()]
    devices = join_options(names, context.language) if names else "-"
    return MatchResult(
        "no_match", text, reply=phrase(context.language, "no_match", text=text, devices=devices)
    )


def _process(
    context: ReadingContext, device: str, parts: list[tuple[Reading, list[PlanStep]]], picked: bool
) -> ProcessPlan:
    language, display = context.language, context.devices[device].display_name
    clauses = list(dict.fromkeys(_sentence_case(reading.clause) for reading, _ in parts))
    spoken = "; ".join(clause[0].lower() + clause[1:] for clause in clauses)
    # Name the device when the sentence alone does not: "all the lights" (one process per
    # light), or "the light" after the user picked one.
    shared = any(len(reading.calls) > 1 for reading, _ in parts)
    named = shared or picked
    detail = f"{spoken} ({display})" if named else spoken
    steps = [step for _, part_steps in parts for step in part_steps]
    last = parts[-1][0]
    answer = last.answers.get(device)
    question = answer is not None or device in last.readouts or device in last.replies
    if question:
        if answer is not None:
            reply = answer.yes
        else:
            reply = last.replies.get(device) or readout_reply(context, device)
        ack = phrase(language, "ack_question", device=display)
        failure = phrase(language, "failure_question", device=display, error="{error}")
    else:
        reply = phrase(language, "done", clause=detail)
        # Processes of one "all the lights" share their ack, so the kernel says it once.
        ack = phrase(language, "ack", clause=spoken if shared else detail)
        failure = phrase(language, "failure", clause=detail, error="{error}")
    plan = Plan(
        steps=steps,
        reply=reply,
        failure=failure,
        ack=ack,
        answer=answer,
        fills_state=device in last.fills_state,
    )
    summary = ". ".join(clauses) + ("?" if question else ".") + (f" This process: {device}." if named else "")
    return ProcessPlan(devices=(device,), summary=summary, plan=plan)


def _sentence_case(clause: str) -> str:
    clause = clause.strip().rstrip(".!?").strip()
    return clause[:1].upper() + clause[1:]
