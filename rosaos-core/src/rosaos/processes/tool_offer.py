"""Which of a granted device's tools a process model is offered.

Every offered tool's schema travels with every model request of the process, so a tool the task
will not use costs prefill time on each of them (``benchmarks/llm_path.py``). Three rules trim
the offer, all decided from the job alone:

- ``GrantedDevice.tools``: the only tools offered (an always-attached device the kernel did not
  ask for comes with its speaking tools only);
- ``GrantedDevice.on_request_tools``: expert tools offered only when the task asks for them, by
  naming one or by a word of the driver's ``on_request_pattern`` (ROS's topic, service, parameter,
  action and node tools for "publish on /cmd_vel", not for "undock and search");
- ``safe_stop``, which every device server has, is the kernel's: its ``stop`` tool, the emergency
  stop and a worker that lost its kernel call it (over their own sessions). A process stops a
  robot with the robot's own ``stop``.

The offline plan runner is not limited: its plan names the exact tools.
"""

from __future__ import annotations

import re
from typing import Any

from pydantic_ai.toolsets import AbstractToolset

from rosaos.processes.jobs import GrantedDevice

KERNEL_ONLY = frozenset({"safe_stop"})
"""Tools of every device that no process model is offered."""


def asks_for_on_request_tools(device: GrantedDevice, task: str) -> bool:
    """Whether ``task`` asks for ``device``'s on-request tools: it names one, or matches the pattern."""
    if not device.on_request_tools:
        return True
    lowered = task.lower()
    if any(re.search(rf"\b{re.escape(name)}\b", lowered) for name in device.on_request_tools):
        return True
    pattern = device.on_request_pattern
    return pattern is not None and re.search(pattern, task, re.IGNORECASE) is not None


def offered_names(device: GrantedDevice, task: str) -> tuple[frozenset[str] | None, frozenset[str]]:
    """The tools offered (None: all) and those withheld, for ``device`` and ``task``."""
    allowed = None if device.tools is None else frozenset(device.tools)
    expert = frozenset() if asks_for_on_request_tools(device, task) else frozenset(device.on_request_tools)
    return allowed, KERNEL_ONLY | expert


def offered_tools(session: AbstractToolset[Any], device: GrantedDevice, task: str) -> AbstractToolset[Any]:
    """``session`` limited to what :func:`offered_names` offers for ``task``."""
    allowed, withheld = offered_names(device, task)
    return session.filtered(
        lambda ctx, tool: (allowed is None or tool.name in allowed) and tool.name not in withheld
    )
