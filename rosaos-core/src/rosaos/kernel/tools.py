"""The kernel agent's only toolset: the process manager, as an internal FastMCP server.

The kernel never touches hardware. Its system-call table is these four tools; device tools are
reachable only from process agents that hold a lease on the device.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Mapping
from typing import Annotated, Any

from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from pydantic import Field

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.drivers import CHANGES, DELETES, READ_ONLY
from rosaos.events.plan import Plan
from rosaos.kernel.launch_cause import CurrentEvent, LaunchCause
from rosaos.models.tool_schemas import ENGINE_ONLY
from rosaos.processes.manager import LaunchRefused, ProcessInfo, ProcessManager

KERNEL_TOOL_NAMES = ("launch_process", "terminate_process", "list_processes", "list_devices")


def build_kernel_tools(
    manager: ProcessManager,
    devices: Callable[[], Mapping[str, DeviceEndpoint]],
    on_launch: Callable[[ProcessInfo], Awaitable[None]] | None = None,
    *,
    current: CurrentEvent | None = None,
    before_start: Callable[[ProcessInfo, LaunchCause | None], Awaitable[None]] | None = None,
    launched_before: Callable[[LaunchCause], Awaitable[int | None]] | None = None,
) -> FastMCP:
    """Build the process-manager server that the kernel agent mounts in-process.

    ``before_start(info, cause)`` runs after the leases are granted and before a worker is told
    to start: the kernel records the launch durably there, so a crash at any later point leaves
    a record (:mod:`rosaos.kernel.orphans`). ``launched_before(cause)`` names the process an
    earlier run of the same event already launched at this step, which is then not launched
    again. ``on_launch(info)`` runs after each launch.
    """
    server = FastMCP("rosaos-kernel", instructions="Process management for the rosaOS kernel.")

    @server.tool(annotations=CHANGES)
    async def launch_process(
        devices: Annotated[
            list[str],
            Field(max_length=16, description="Instance names."),
        ],
        task: Annotated[
            str | None,
            Field(
                max_length=4000,
                description=(
                    "Self-contained: the agent sees nothing else. Omit it when the user's one "
                    "sentence, as said, is the whole task."
                ),
            ),
        ] = None,
        then: Annotated[
            str | None,
            Field(
                max_length=2000,
                description=("A next step you launch only if this one succeeds; not done by this process."),
            ),
        ] = None,
        plan: Annotated[
            Plan | None,
            Field(
                description="The offline engine's exact device calls; a model is not shown it.",
                json_schema_extra={ENGINE_ONLY: True},
            ),
        ] = None,
    ) -> dict[str, Any]:
        """Start a process agent; its result comes as a [Process callback]. A device another process holds is refused."""
        then = " ".join(then.split()) if then is not None and then.strip() else None
        if task is None or not task.strip():
            said = current.said if current is not None else None
            if said is None or not said.strip():
                raise ToolError(
                    "give the task: it may be left out only when the event is one sentence of the "
                    "user's that is the whole task, and this one is not"
                )
            task = said
        cause = current.next_cause() if current is not None else None
        if cause is not None and launched_before is not None:
            earlier = await launched_before(cause)
            if earlier is not None:
                raise ToolError(
                    f"this command was already launched as process {earlier} before the kernel "
                    "restarted; that run is reported on its own and is not started a second time"
                )
        start_hook = None
        if before_start is not None:
            hook = before_start

            async def start_hook(info: ProcessInfo) -> None:
                await hook(info, cause)

        try:
            info = await manager.launch(task, list(devices), before_start=start_hook, plan=plan, then=then)
        except LaunchRefused as refusal:
            raise ToolError(str(refusal)) from None
        if on_launch is not None:
            await on_launch(info)
        return {"process_id": info.id, "devices": info.devices, "state": info.state}

    @server.tool(annotations=DELETES)
    async def terminate_process(process_id: Annotated[int, Field(ge=1)]) -> dict[str, Any]:
        """Kill a running process and release its devices."""
        try:
            info = await manager.terminate(process_id)
        except KeyError as error:
            raise ToolError(str(error.args[0]) if error.args else f"no process {process_id}") from None
        return _process_data(info)

    @server.tool(annotations=READ_ONLY)
    async def list_processes() -> list[dict[str, Any]]:
        """The running processes: id, task, devices, state."""
        return [_process_data(info) for info in manager.list()]

    @server.tool(annotations=READ_ONLY)
    async def list_devices() -> list[dict[str, Any]]:
        """The devices: name, driver, description, availability, holder."""
        holders: dict[str, list[int]] = {}
        for info in manager.list():
            for name in info.devices:
                holders.setdefault(name, []).append(info.id)
        return [
            {
                "name": endpoint.name,
                "driver": endpoint.driver,
                "description": endpoint.description,
                "concurrency": endpoint.concurrency,
                "always_attached": endpoint.always_attached,
                "available": endpoint.grantable,
                "status": endpoint.status,
                "held_by": holders.get(endpoint.name, []),
            }
            for endpoint in devices().values()
        ]

    return server


def _process_data(info: ProcessInfo) -> dict[str, Any]:
    return info.model_dump(mode="json")
