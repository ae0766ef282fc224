"""The kernel tools that need no lease: ``stop`` (preempts) and ``device_state`` (reads).

A person's "stop" and a question about a device ("is the turtlebot docked?") must work while
another process holds the device, so neither goes through ``launch_process``. Both run in the
kernel, on the kernel's own tool server, and both engines use them: the offline engine plans
calls to them, and an LLM kernel is told when to call them (:mod:`rosaos.kernel.agent`).
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable, Mapping
from typing import Annotated, Any

from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from mcp.types import ToolAnnotations
from pydantic import Field

from rosaos.devices.client import DeviceClient
from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.drivers import READ_ONLY, DeviceError
from rosaos.intents.grammar.state_words import called, describe
from rosaos.kernel.stopping import StopError, Stopper, StopReport, describe_task
from rosaos.processes.manager import ProcessManager

STOP_TOOL_NAMES = ("stop", "device_state")
STATE_TIMEOUT = 3.0

STOPS = ToolAnnotations(readOnlyHint=False, destructiveHint=True, idempotentHint=True)


def add_stop_tools(
    server: FastMCP,
    stopper: Stopper,
    manager: ProcessManager,
    endpoints: Callable[[], Mapping[str, DeviceEndpoint]],
    merge: Callable[[StopReport], Awaitable[StopReport]] | None = None,
) -> None:
    """Register ``stop`` and ``device_state`` on the kernel's tool server.

    ``merge`` adds what a stop at intake already did for the event being handled
    (:mod:`rosaos.kernel.stop_at_intake`) to the report the model reads.
    """

    @server.tool(annotations=STOPS)
    async def stop(
        devices: Annotated[
            list[str] | None,
            Field(
                max_length=32,
                description="Instance names ('stop the dog': ['dog']); omit for a bare 'stop': robots "
                "in motion, speech, music, every process.",
            ),
        ] = None,
    ) -> dict[str, Any]:
        """Stop at once, with no lease: ends the processes holding the devices and halts them.

        Returns 'summary' for the user.
        """
        try:
            report = await stopper.stop(devices or [])
        except StopError as error:
            raise ToolError(str(error)) from None
        if merge is not None:
            report = await merge(report)
        return report.model_dump(mode="json")

    @server.tool(annotations=READ_ONLY)
    async def device_state(
        device: Annotated[
            str | None,
            Field(
                max_length=200,
                description="Instance name; omit for every device.",
            ),
        ] = None,
    ) -> dict[str, Any]:
        """Read a device's state, with no lease, also while a process holds it.

        Returns state, 'said' (words and degrees: prefer it) and 'held_by'.
        """
        known = endpoints()
        if device is not None and device not in known:
            raise ToolError(f"no device named {device!r}; the devices are {', '.join(known)}")
        names = [device] if device is not None else list(known)
        running = manager.list()
        read = await asyncio.gather(*(_read(known[name], running) for name in names))
        if device is not None:
            return read[0]
        return {"devices": read}


async def _read(endpoint: DeviceEndpoint, running: list[Any]) -> dict[str, Any]:
    held_by = [
        {"id": info.id, "task": describe_task(info.task)}
        for info in running
        if endpoint.name in info.devices and not endpoint.always_attached
    ]
    answer: dict[str, Any] = {
        "device": endpoint.name,
        "called": called(endpoint.name, endpoint.driver),
        "status": endpoint.status,
        "held_by": held_by,
    }
    if endpoint.url is None:
        return answer | {"state": None, "said": [f"The {_spoken(endpoint.name)} is {endpoint.status}."]}
    client = DeviceClient(endpoint.url, endpoint.token, STATE_TIMEOUT, endpoint.name)
    try:
        state = await asyncio.wait_for(client.get_state(), STATE_TIMEOUT)
    except (DeviceError, TimeoutError) as error:
        problem = str(error) or f"it did not answer within {STATE_TIMEOUT:g} s"
        return answer | {"state": None, "said": [f"I could not read the {_spoken(endpoint.name)}: {problem}"]}
    return answer | {"state": state, "said": describe(endpoint.name, state, endpoint.driver)}


def _spoken(name: str) -> str:
    return name.replace("_", " ")
