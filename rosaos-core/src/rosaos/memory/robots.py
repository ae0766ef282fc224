"""The kernel's read of where a robot is, for saving a place and checking one before it is used.

Reading state needs no lease (see ``docs/architecture.md``): the kernel calls a robot's
read-only ``get_pose`` directly, as the dashboard reads ``get_state``. Moving it is a process
like any other, launched with a plan (:func:`go_to_task`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from rosaos.devices.client import DeviceClient
from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.drivers import DeviceError
from rosaos.events.plan import Plan, PlanStep
from rosaos.memory.store import MemoryRequestError, Place

POSE_TOOL, GO_TOOL = "get_pose", "go_to"
READ_TIMEOUT = 5.0

Endpoints = Callable[[], Mapping[str, DeviceEndpoint]]


async def robots(endpoints: Endpoints) -> list[str]:
    """The served devices that can say where they are and go to a pose (``get_pose`` and ``go_to``)."""
    found = []
    for endpoint in endpoints().values():
        if endpoint.url is None:
            continue
        try:
            tools = await DeviceClient(endpoint.url, endpoint.token, READ_TIMEOUT, endpoint.name).list_tools()
        except DeviceError:
            continue
        names = {tool.name for tool in tools}
        if POSE_TOOL in names and GO_TOOL in names:
            found.append(endpoint.name)
    return found


async def read_pose(endpoints: Endpoints, device: str) -> dict[str, Any]:
    """``device``'s pose with its frame and anchor; :class:`MemoryRequestError` when it cannot say."""
    endpoint = endpoints().get(device)
    if endpoint is None or endpoint.url is None:
        known = ", ".join(endpoints()) or "none"
        raise MemoryRequestError(f"there is no robot {device!r} running here (devices: {known})")
    try:
        pose = await DeviceClient(endpoint.url, endpoint.token, READ_TIMEOUT, device).call(POSE_TOOL)
    except DeviceError as error:
        raise MemoryRequestError(f"cannot tell where {device} is: {error}") from None
    if not isinstance(pose, dict) or not {"x", "y", "frame", "anchor"} <= set(pose):
        raise MemoryRequestError(f"{device}'s get_pose did not return a pose with its frame")
    return pose


async def choose_robot(endpoints: Endpoints, device: str | None) -> tuple[str, dict[str, Any]]:
    """The robot a place request means, and its pose.

    Named: that one. Otherwise the only robot, or the only one localized on a map (places are
    best kept on a map: they outlive restarts there). Several candidates: ask which.
    """
    if device is not None:
        return device, await read_pose(endpoints, device)
    candidates = await robots(endpoints)
    if not candidates:
        raise MemoryRequestError(
            "no robot that knows its position is running, so there is no spot to remember"
        )
    poses = {}
    for name in candidates:
        try:
            poses[name] = await read_pose(endpoints, name)
        except MemoryRequestError:
            continue
    on_a_map = [name for name, pose in poses.items() if pose["frame"] != "odom"]
    if len(poses) == 1 or len(on_a_map) == 1:
        name = next(iter(poses)) if len(poses) == 1 else on_a_map[0]
        return name, poses[name]
    raise MemoryRequestError(f"which robot? Say it with the robot's name: {' or '.join(candidates)}")


def frame_refusal(place: Place, pose: dict[str, Any], device: str) -> str | None:
    """Why ``device`` must not drive to ``place`` from where it is now, or None when the frames agree."""
    if place.anchor == pose["anchor"]:
        return None
    if place.frame == "odom":
        why = (
            f"{place.name} was saved on {place.device}'s odometry before it last restarted; odometry "
            "starts over where the robot boots, so those coordinates would now name a different spot"
        )
    elif pose["frame"] == "odom":
        why = f"{place.name} is on a map ({place.anchor}), and {device} is not localized on any map now"
    else:
        why = f"{place.name} was saved on another map ({place.anchor}); {device} is on {pose['anchor']}"
    return (
        f"I won't drive there: {why}. Stand the robot at {place.name} and say "
        f"'remember this spot as {place.name}' again."
    )


def go_to_task(place: Place, device: str) -> tuple[str, Plan]:
    """The task and plan that drive ``device`` to ``place`` (a plan the offline engine runs)."""
    args: dict[str, Any] = {"x": place.x, "y": place.y, "frame_anchor": place.anchor}
    if place.yaw is not None:
        args["yaw"] = place.yaw
    plan = Plan(
        steps=[PlanStep(device=device, tool=GO_TOOL, args=args)],
        reply=f"I'm at {place.name}.",
        failure=f"I couldn't get to {place.name}: {{error}}",
        ack=f"On my way to {place.name}.",
    )
    summary = (
        f"Drive {device} to the place called {place.name}: x {place.x:g}, y {place.y:g} in the "
        f"{place.frame} frame (go_to with frame_anchor {place.anchor!r}, so another frame is refused)."
    )
    return summary, plan
