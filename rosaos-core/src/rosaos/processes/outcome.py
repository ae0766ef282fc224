"""How a process agent's run ended, judged on what its device calls did, not on what the model said.

A model that writes "Done, the light is on" has proved nothing. The worker keeps its own record of
every device call (:class:`~rosaos.processes.tool_calls.ToolCallLog`) and decides the status from
it (issue 22):

- a failed call that no later success of the same tool made good: ``error``, with the device's
  own message;
- a model ran, but no call to a device the task was granted for succeeded: ``unverified``;
- the task asked for a change ("turn on …", "set …", "undock …") but every successful call only
  read (``readOnlyHint``), or only spoke through an always-attached device: ``unverified``.

Whether a task asks for a change is read from its words (:func:`asks_for_change`): the kernel
writes the task, so an LLM kernel's phrasing decides. A task with no change verb at the start of
a clause, a question, or a conditional ("if it is off, turn it on") is not held to the last rule,
only to the first two: a change it may rightly skip is not demanded.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import NamedTuple

from rosaos.processes.jobs import GrantedDevice, ProcessStatus
from rosaos.processes.tool_calls import ToolCallLog
from rosaos.receipts import error_text

CHANGE_VERBS = frozenset(
    {
        "turn", "switch", "set", "dim", "brighten", "make", "change", "raise", "lower", "increase",
        "decrease", "drive", "move", "go", "walk", "rotate", "spin", "navigate", "undock", "dock",
        "play", "pause", "resume", "skip", "stop", "open", "close", "lock", "unlock", "start",
        "arm", "disarm", "lift", "nod", "wave", "put", "bring", "return", "head",
    }
)  # fmt: skip
"""Verbs that, opening a clause of a task, ask a device to change something."""

_CLAUSES = re.compile(r"[.;:!,]|\b(?:and|then)\b")
_CONDITIONAL = re.compile(r"\b(?:if|unless|when(?:ever)?|in case|once)\b")

NO_CALL = (
    "the process agent said it was done, but it made no successful device call, so nothing shows "
    "that it happened; its report is not a result"
)
ONLY_READ = (
    "the task asked for a change, but the process agent's successful calls only read state ({calls}); "
    "nothing shows the change happened, so its report is not a result"
)


class Outcome(NamedTuple):
    """A process's final status and the reason for it (``None`` when it ended ``ok``)."""

    status: ProcessStatus
    error: str | None


def asks_for_change(task: str) -> bool:
    """Whether ``task`` plainly asks a device to change something, with no condition attached.

    ``"Turn on the kitchen light."`` and ``"Undock, then search for a person"`` do;
    ``"Is the light on?"``, ``"Take a picture and describe it"`` and ``"If the lamp is off, turn it
    on"`` do not (the last may rightly do nothing).
    """
    text = task.strip().lower()
    first = text.split("\n", 1)[0]  # the kernel's own words; appended notes (a follow-up) follow
    if not first or first.rstrip().endswith("?") or _CONDITIONAL.search(first):
        return False
    for clause in _CLAUSES.split(first):
        words = clause.split()
        if words[:1] == ["please"]:
            words = words[1:]
        if words and words[0] in CHANGE_VERBS:
            return True
    return False


def judge(
    status: ProcessStatus,
    error: str | None,
    *,
    task: str,
    devices: Sequence[GrantedDevice],
    calls: ToolCallLog,
    model_ran: bool,
) -> Outcome:
    """The process's status from its calls: ``status``/``error`` unless the calls contradict ``ok``.

    ``model_ran`` is false for an offline plan run, whose steps are the plan's, not a model's word.
    Calls to a device granted only its speaking tools (``tools`` set: the always-attached robot)
    show nothing about the task's devices, so they count as neither proof nor change.
    """
    if status != "ok":
        return Outcome(status, error)
    failed = calls.unresolved_failure()
    if failed is not None:  # the model may have written a polite sentence about it
        return Outcome("error", f"{failed.device}: {failed.tool} failed: {error_text(failed.error or '')}")
    if not model_ran:
        return Outcome(status, error)
    asked = {device.name for device in devices if device.tools is None}
    succeeded = [call for call in calls.calls if call.ok and (call.device in asked or not asked)]
    if devices and not succeeded:
        return Outcome("unverified", NO_CALL)
    if asked and asks_for_change(task) and not any(call.changes for call in succeeded):
        names = ", ".join(sorted({f"{call.device}.{call.tool}" for call in succeeded}))
        return Outcome("unverified", ONLY_READ.format(calls=names))
    return Outcome(status, error)
