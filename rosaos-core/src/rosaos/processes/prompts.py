"""The process agent's system prompt: base prompt, one section per device, then the kernel's task.

The kernel agent decides *what* to do and which devices to grant; the process agent does it with
exactly the tools of those devices. Its prompt therefore says how to behave (the base prompt),
what to do (the task, verbatim from ``launch_process``), and what each granted device is and how
to drive it (the device prompt that the driver ships).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from rosaos.events.plan import plan_text
from rosaos.processes.jobs import GrantedDevice, WorkerJob
from rosaos.processes.tool_list import DeviceTools

DEFAULT_PROCESS_PROMPT = """\
You are a process agent in rosaOS, an operating system for robots and smart devices.
The kernel gave you one task and the devices it needs. Do the task with those devices' tools, \
then reply with one short sentence saying what you did and the resulting state. The kernel tells \
the user that sentence as it is (it may be spoken aloud), so write it for them, and do not also \
speak it with a tool. Write it in the same response as the tool calls that finish the task: when \
they all succeed, that is your report and the process ends; if one fails, you are asked again.

- Do exactly the task: do not touch devices or settings the task does not ask for.
- A tool's result shows the device's new state; read the state first (get_state) only when the \
task depends on it.
- Tool arguments are bounded by the device's real limits; if a value is out of range, use the \
nearest valid one and say so.
- If a tool fails, read its message: retry once if it says how to fix the call, otherwise stop \
and report what failed and why.
- A task is done only when a tool call did it. Never invent a device state or a result you did \
not get from a tool.
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


def process_system_prompt(
    base_prompt: str,
    task: str,
    devices: Sequence[GrantedDevice],
    tools: Mapping[str, DeviceTools] | None = None,
) -> str:
    """Assemble the process agent's system prompt for ``task`` with ``devices`` granted, task last.

    Each device section is headed by its instance name and description, followed by the driver's
    device prompt and the device's tool list, written from its MCP metadata (``tools``, by
    instance; :mod:`rosaos.processes.tool_list`), limited to the tools the process is offered.
    With more than one device the tool names are prefixed by the instance name
    (``kitchen_light_set_color``), and the section says so, so the model can tell them apart.
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
            listed = tools.get(device.name) if tools is not None else None
            tool_list = listed.render(device.tools) if listed is not None else ""
            body = f"{device.prompt.strip()}\n\n{tool_list}" if tool_list else device.prompt.strip()
            parts.append(f"{heading}\n\n{body}")
    # The task comes last: what stays the same for every task on these devices (the base prompt,
    # the device sections, and the tool schemas before them) is then a prefix that a local model
    # server caches (llama.cpp, vLLM, Ollama), so only the task is prefilled anew.
    parts.append(f"# Your task\n{task.strip()}")
    return "\n\n".join(parts) + "\n"
