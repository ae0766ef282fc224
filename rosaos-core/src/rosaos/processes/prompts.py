"""The process agent's system prompt: base prompt, one section per device, then the kernel's task.

The kernel agent decides *what* to do and which devices to grant; the process agent does it with
exactly the tools of those devices. Its prompt therefore says how to behave (the base prompt),
what to do (the task, verbatim from ``launch_process``), and what each granted device is and how
to drive it (the device prompt that the driver ships).
"""

from __future__ import annotations

from collections.abc import Sequence

from rosaos.events.plan import plan_text
from rosaos.processes.jobs import GrantedDevice, WorkerJob

DEFAULT_PROCESS_PROMPT = """\
You are a process agent of rosaOS, an operating system for robots and smart devices. Do the task \
below with your devices' tools. Beside the calls that finish it, write "Done." or, if the results \
hold what the user asked to know or would not expect, one short sentence saying it: the user is \
told it as it is, maybe aloud. If the calls succeed the process ends there; if one fails you are \
asked again.

- Do only the task: no other device or setting.
- Results show the new state; read the state first only when the task depends on it.
- A value out of a tool's range: use the nearest valid one and say so.
- A failed call: retry once if its message says how, else report what failed and why.
- Only a successful call does a task: never claim a state or result no tool gave you.
"""


def base_process_prompt(configured: str | None) -> str:
    """The base process prompt: ``[kernel] process_prompt`` from the config, or the built-in default."""
    if configured is not None and configured.strip():
        return configured
    return DEFAULT_PROCESS_PROMPT


def tool_prefix(device: str) -> str:
    """The prefix a device's tool names get when a process holds more than one device."""
    return device


FOLLOW_UP_HEADING = (
    "Kernel follow-up (not for this process; the kernel launches it only if this task succeeds):"
)


def job_text(job: WorkerJob) -> str:
    """The task as a process model reads it: the kernel's words, then the plan and the follow-up.

    The plan and the follow-up travel as fields of the job (and come back on the callback); this
    text is only for a model to read, never parsed."""
    parts = [job.task.strip()]
    if job.plan is not None:
        parts.append(plan_text(job.plan))
    if job.then:
        parts.append(f"{FOLLOW_UP_HEADING} {' '.join(job.then.split())}")
    return "\n\n".join(parts)


def process_system_prompt(base_prompt: str, task: str, devices: Sequence[GrantedDevice]) -> str:
    """Assemble the process agent's system prompt for ``task`` with ``devices`` granted, task last.

    Each device section is headed by its instance name and description, followed by the driver's
    device prompt: what no schema says (when to prefer which tool, what "a bit" means). The tools
    themselves are not listed: the model is sent every offered tool's name, parameters and
    description as its schema, and a list here would say it all a second time on every request
    (issue 22: 1.5 KB of a light switch's 4 KB prompt). With more than one device the tool names
    are prefixed by the instance name (``kitchen_light_set_color``), and the section says so.
    """
    parts = [base_prompt.strip()]
    if not devices:
        parts.append("# Your devices\nYou hold no devices for this task, so you have no tools.")
    else:
        prefixed = len(devices) > 1
        names = ", ".join(device.name for device in devices)
        parts.append(f"# Your devices\nYou hold: {names}.")
        for device in devices:
            heading = f"## {device.name} ({device.driver})\n{device.description.strip()}"
            if prefixed:
                heading += f"\nIts tools are named `{tool_prefix(device.name)}_<tool>`."
            parts.append(f"{heading}\n\n{device.prompt.strip()}")
    # The task comes last: what stays the same for every task on these devices (the base prompt,
    # the device sections, and the tool schemas before them) is then a prefix that a local model
    # server caches (llama.cpp, vLLM, Ollama), so only the task is prefilled anew.
    parts.append(f"# Your task\n{task.strip()}")
    return "\n\n".join(parts) + "\n"
