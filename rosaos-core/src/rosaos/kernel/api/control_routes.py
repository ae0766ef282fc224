"""The card controls' route: a person presses a control on a device card, a process makes the call.

``POST /devices/{name}/controls/{index}`` turns the card's control (:mod:`rosaos.card_controls`)
and the person's value into one tool call, and launches a process whose plan is that
call. So a control is no back door: it takes the device's lease (a device another process holds
exclusively is refused with the holder named), it is refused while the emergency stop is latched,
its receipt lands in the activity log (``rosaos log``, the page's Activity), and the kernel says
nothing when it succeeds (the plan is ``quiet``) but tells the user when it fails. A control
declared ``preempts`` (a robot's Stop) first terminates the processes holding the device.

Registered on the protected router of :mod:`rosaos.kernel.api.routes` (the bearer token applies).
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import HTTPException
from fastapi import Path as FastPath
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from rosaos.card_controls import CardControl, ControlValueError
from rosaos.events.plan import Plan, PlanStep
from rosaos.kernel.api.routes import Runtime, protected
from rosaos.processes.manager import LaunchRefused


class ControlPress(BaseModel):
    """What a person chose: a toggle's true/false, a slider's number, an option, a text; nothing for a button."""

    model_config = ConfigDict(extra="forbid")

    value: bool | int | float | str | None = None


class ControlStarted(BaseModel):
    """The process that makes the control's call; its end shows in Activity like any other."""

    process_id: int
    task: str = Field(description="What the process does, in words.")
    tool: str
    arguments: dict[str, Any]


@protected.post(
    "/devices/{name}/controls/{index}",
    status_code=202,
    responses={
        404: {"description": "No such device, or its card has no control with this index"},
        409: {"description": "The device is busy (held by another process) or unavailable"},
        422: {"description": "A value the control cannot send"},
        423: {"description": "The emergency stop is latched: no control runs until a person resets it"},
    },
)
async def press_control(
    name: Annotated[str, FastPath(max_length=100)],
    index: Annotated[int, FastPath(ge=0, le=100)],
    runtime: Runtime,
    body: ControlPress | None = None,
) -> ControlStarted:
    """Press control ``index`` of device ``name``'s card (``GET /devices`` lists them under ``card.controls``)."""
    control = await _control(runtime, name, index)
    value = (body or ControlPress()).value
    try:
        tool, arguments = control.call(value)
    except ControlValueError as error:
        raise HTTPException(422, str(error)) from None
    latch = runtime.emergency_stop_state()
    if latch.latched:
        raise HTTPException(
            423,
            f"the emergency stop is latched ({latch.reason}): controls are refused until a person "
            "resets it (the Reset button on the page, or `rosaos estop --reset`)",
        )
    if control.preempts:
        for process in await runtime.processes():
            if name in process.devices and process.state == "running":
                await runtime.terminate(process.id)
    summary = f"{control.describe(value)} on the {name.replace('_', ' ')} (from its card on the web page)."
    plan = Plan(
        steps=[PlanStep(device=name, tool=tool, args=arguments)],
        reply="Done.",
        failure=f"{control.label} on the {name.replace('_', ' ')} failed: {{error}}",
        quiet=True,
    )
    try:
        info = await runtime.launch(summary, [name], plan)
    except LaunchRefused as refusal:
        raise HTTPException(409, str(refusal)) from None
    return ControlStarted(process_id=info.id, task=summary, tool=tool, arguments=arguments)


async def _control(runtime: Runtime, name: str, index: int) -> CardControl:
    device = next((device for device in await runtime.devices() if device.name == name), None)
    if device is None:
        raise HTTPException(404, f"no device {name!r}: GET /devices lists them")
    controls = (device.card or {}).get("controls") or []
    if index >= len(controls):
        raise HTTPException(404, f"the card of {name!r} has {len(controls)} controls; {index} is not one")
    try:
        return CardControl.model_validate(controls[index])
    except ValidationError as error:  # the kernel wrote it from the driver's own declaration
        raise HTTPException(500, f"the card control of {name!r} is not valid: {error}") from None
