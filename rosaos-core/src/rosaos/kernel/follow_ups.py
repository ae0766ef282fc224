"""Follow-ups for an LLM kernel: ``launch_process(..., then=...)`` and how the note reads.

The follow-up is written into the process's task, addressed to the kernel, so it returns with the
``[Worker callback]`` (whose ``task=`` the kernel reads) and survives a kernel restart in the event
store. The process agent sees the note too, but holds none of the follow-up's devices; the note
tells it the step is not its own. The offline engine plans follow-ups itself, in the task's
``rosaos-plan`` block (:mod:`rosaos.intents.planning.followups`).
"""

from __future__ import annotations

FOLLOW_UP_HEADING = (
    "Kernel follow-up (not for this process; the kernel launches it only if this task succeeds):"
)


def attach_follow_up(task: str, then: str) -> str:
    """``task`` with the kernel's follow-up note appended."""
    return f"{task.rstrip()}\n\n{FOLLOW_UP_HEADING} {' '.join(then.split())}"


def follow_up_of(task: str | None) -> str | None:
    """The follow-up note in ``task``, if any."""
    if not task or FOLLOW_UP_HEADING not in task:
        return None
    return task.rsplit(FOLLOW_UP_HEADING, 1)[1].strip() or None
