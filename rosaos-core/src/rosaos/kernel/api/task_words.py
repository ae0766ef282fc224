"""A process's task as people read it: the sentence, and what the kernel will do after it.

A task carries more than its sentence: the offline engine's ``rosaos-plan`` block, or an LLM
kernel's follow-up note (``launch_process(..., then=...)``). The web page shows the sentence and
"then: turn the lamp green", never the block or the note.
"""

from __future__ import annotations

from rosaos.intents.planning.plan import PlanError, decode_plan, task_summary
from rosaos.kernel.follow_ups import FOLLOW_UP_HEADING, follow_up_of


def task_words(task: str) -> tuple[str, str | None]:
    """``(summary, then)``: the task's sentence, and its follow-up in words (None without one)."""
    summary = task_summary(task).split(FOLLOW_UP_HEADING, 1)[0].strip()
    summary = summary.split("\n\n", 1)[0].strip()
    then = follow_up_of(task)
    try:
        plan = decode_plan(task)
    except PlanError:
        plan = None
    if plan is not None and plan.then is not None:
        then = plan.then.summary
    return summary, then
