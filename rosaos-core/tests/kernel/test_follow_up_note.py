"""An LLM kernel's follow-up: launch_process(..., then=...) writes it into the task, addressed to the kernel."""

from __future__ import annotations

from rosaos.kernel.agent import DEFAULT_KERNEL_PROMPT
from rosaos.kernel.follow_ups import FOLLOW_UP_HEADING, attach_follow_up, follow_up_of


def test_the_note_rides_in_the_task_and_reads_back() -> None:
    task = attach_follow_up("Undock the turtlebot and search for a person.", "turn the lamp  green\n")
    assert task.startswith("Undock the turtlebot and search for a person.\n\n" + FOLLOW_UP_HEADING)
    assert follow_up_of(task) == "turn the lamp green"
    assert follow_up_of("Undock the turtlebot.") is None
    assert follow_up_of(None) is None


def test_the_kernel_prompt_says_how_to_use_it() -> None:
    assert 'then="<the next step>"' in DEFAULT_KERNEL_PROMPT
    assert "only if status=ok" in DEFAULT_KERNEL_PROMPT
