"""The kernel's memory tools: named places, and what people told it.

Added to the kernel's own FastMCP server next to the process and timer tools, so the offline
engine and an LLM kernel use the same ones:

- ``remember_place``, ``list_places``, ``forget_place``, ``go_to_place`` (it launches a process
  that calls the robot's ``go_to`` with the place's frame anchor; the callback says how it went);
- ``remember``, ``recall``, ``forget``: facts, aliases and preferences;
- ``recall_sightings``, ``show_sighting`` ("show me": the picture's address, which the page shows),
  ``forget_sightings``: what the robots saw.
"""

from __future__ import annotations

import time
from collections.abc import Awaitable, Callable
from datetime import datetime
from typing import Annotated, Any

from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from pydantic import Field

from rosaos.drivers import CHANGES, DELETES, READ_ONLY
from rosaos.events.plan import Plan
from rosaos.memory.memory_phrases import MEMORY_TOOL_NAMES
from rosaos.memory.robots import Endpoints, choose_robot, frame_refusal, go_to_task, read_pose
from rosaos.memory.sightings import SightingLog, ago
from rosaos.memory.store import NAME_MAX, MemoryRequestError, MemoryStore, NoteKind, Place
from rosaos.processes.manager import LaunchRefused, ProcessInfo

__all__ = ["MEMORY_TOOL_NAMES", "add_memory_tools"]

PlaceName = Annotated[str, Field(min_length=1, max_length=NAME_MAX, description="e.g. 'the kitchen'")]
Device = Annotated[
    str | None,
    Field(max_length=100, description="The robot; omit if there is one."),
]
Coordinate = Annotated[float | None, Field(ge=-1000, le=1000, allow_inf_nan=False)]
Launch = Callable[[str, list[str], Plan], Awaitable[ProcessInfo]]


def place_data(place: Place) -> dict[str, Any]:
    """A place as the tools return it."""
    return place.model_dump(mode="json") | {
        "saved": time.strftime("%Y-%m-%d %H:%M", time.localtime(place.saved_at))
    }


def add_memory_tools(
    server: FastMCP, store: MemoryStore, endpoints: Endpoints, launch: Launch, sightings: SightingLog
) -> None:
    """Register the memory tools on the kernel's tool server."""

    @server.tool(annotations=READ_ONLY)
    async def recall_sightings(
        place: Annotated[
            str | None, Field(max_length=NAME_MAX, description="Only near this named place.")
        ] = None,
        today: Annotated[bool, Field(description="Only since midnight.")] = False,
    ) -> dict[str, Any]:
        """Who the robots saw, newest first."""
        known = store.place(place) if place else None
        named = known.name if known is not None else place
        midnight = datetime.now().astimezone().replace(hour=0, minute=0, second=0, microsecond=0)
        since = midnight.timestamp() if today else None
        found = sightings.recent(named, since)
        return {
            "sightings": [s.model_dump(mode="json") | {"ago": ago(s.at)} for s in found],
            "kept_days": sightings.keep_days,
        }

    @server.tool(annotations=READ_ONLY)
    async def show_sighting(
        sighting_id: Annotated[int | None, Field(ge=1, description="Default: the newest.")] = None,
    ) -> dict[str, Any]:
        """Show a sighting's picture on the page: put the returned ``picture`` address in your reply."""
        # /sightings/{id}/picture on the kernel: the page shows the picture under the reply that
        # names it (sighting_pictures.js); the picture itself never goes to the model.
        found = sightings.get(sighting_id) if sighting_id else sightings.with_picture()
        if found is None:
            which = f"sighting {sighting_id}" if sighting_id else "sighting with a picture"
            raise ToolError(
                f"I have no {which} in the last {sightings.keep_days:g} days; recall_sightings lists them"
            )
        if sightings.picture(found) is None:
            raise ToolError(
                f"sighting {found.id} has no picture on this machine (none was taken, or it was deleted)"
            )
        return found.model_dump(mode="json") | {
            "ago": ago(found.at),
            "picture": f"/sightings/{found.id}/picture",
        }

    @server.tool(annotations=DELETES)
    async def forget_sightings() -> dict[str, Any]:
        """Forget every sighting (the pictures stay)."""
        return {"forgotten": sightings.clear()}

    @server.tool(annotations=CHANGES)
    async def remember_place(
        name: PlaceName,
        device: Device = None,
        x: Annotated[Coordinate, Field(description="Metres; omit x, y for here.")] = None,
        y: Coordinate = None,
        yaw: Annotated[float | None, Field(ge=-7, le=7, allow_inf_nan=False, description="Radians.")] = None,
    ) -> dict[str, Any]:
        """Name a place: where the robot is, or x, y in its current frame (kept with the place)."""
        if (x is None) != (y is None):
            raise ToolError("give both x and y, or neither (then the robot's current spot is saved)")
        try:
            robot, pose = await choose_robot(endpoints, device)
            given = x is not None and y is not None
            place = Place(
                name=name.strip(),
                device=robot,
                frame=pose["frame"],
                anchor=pose["anchor"],
                x=x if x is not None else float(pose["x"]),
                y=y if y is not None else float(pose["y"]),
                yaw=yaw if given else (yaw if yaw is not None else pose.get("yaw")),
                saved_at=time.time(),
            )
            return place_data(store.save_place(place))
        except MemoryRequestError as error:
            raise ToolError(str(error)) from None

    @server.tool(annotations=READ_ONLY)
    async def list_places() -> list[dict[str, Any]]:
        """The named places."""
        return [place_data(place) for place in store.places()]

    @server.tool(annotations=DELETES)
    async def forget_place(name: PlaceName) -> dict[str, Any]:
        """Delete a named place."""
        try:
            return place_data(store.forget_place(name))
        except MemoryRequestError as error:
            raise ToolError(str(error)) from None

    @server.tool(annotations=CHANGES)
    async def go_to_place(name: PlaceName, device: Device = None) -> dict[str, Any]:
        """Send a robot to a named place (by default the one that saved it); result as a [Process callback]."""
        try:
            place = store.require_place(name)
            robot = device or place.device
            refusal = frame_refusal(place, await read_pose(endpoints, robot), robot)
        except MemoryRequestError as error:
            raise ToolError(str(error)) from None
        if refusal is not None:
            raise ToolError(refusal)
        try:
            task, plan = go_to_task(place, robot)
            info = await launch(task, [robot], plan)
        except LaunchRefused as refused:
            raise ToolError(str(refused)) from None
        return {"process_id": info.id, "devices": info.devices, "place": place_data(place)}

    @server.tool(annotations=CHANGES)
    async def remember(
        kind: Annotated[
            NoteKind,
            Field(description="fact ('my name is Sam'), alias (key 'rex', value 'the dog') or preference."),
        ],
        key: Annotated[str, Field(min_length=1, max_length=100, description="'name', 'rex'")],
        value: Annotated[str, Field(min_length=1, max_length=500)],
        said: Annotated[str | None, Field(max_length=500, description="Their sentence.")] = None,
    ) -> dict[str, Any]:
        """Remember what a person told you; the same kind and key replaces it. An alias renames a device."""
        try:
            note = store.save_note(kind, key, value, said or f"{key}: {value}")
        except MemoryRequestError as error:
            raise ToolError(str(error)) from None
        return note.model_dump(mode="json")

    @server.tool(annotations=READ_ONLY)
    async def recall(
        about: Annotated[
            str | None, Field(max_length=200, description="Words to look for; omit for all.")
        ] = None,
    ) -> dict[str, Any]:
        """What you remember: facts, aliases, preferences, places."""
        words = (about or "").lower().split()

        def hit(text: str) -> bool:
            return all(word in text.lower() for word in words)

        notes = [
            n.model_dump(mode="json") for n in store.notes() if hit(f"{n.kind} {n.key} {n.value} {n.said}")
        ]
        places = [place_data(p) for p in store.places() if hit(p.name)]
        return {"notes": notes, "places": places}

    @server.tool(annotations=DELETES)
    async def forget(
        matching: Annotated[
            str,
            Field(min_length=1, max_length=200, description="Words of it ('my name')."),
        ],
    ) -> list[dict[str, Any]]:
        """Forget what people told you that has all these words."""
        gone = store.forget_notes(matching)
        if not gone:
            raise ToolError(f"I don't remember anything about {matching!r}; recall lists what I know")
        return [note.model_dump(mode="json") for note in gone]


def memory_summary(store: MemoryStore, limit: int = 2000) -> str:
    """What the kernel knows, for an LLM's prompt: places and notes, at most ``limit`` characters."""
    lines = [f"- {note.kind} {note.key}: {note.value}" for note in store.notes()]
    lines += [f"- place {p.name} ({p.device}, {p.frame})" for p in store.places()]
    if not lines:
        return ""
    text, kept = "", 0
    for line in lines:
        if len(text) + len(line) + 1 > limit:
            break
        text += line + "\n"
        kept += 1
    more = f"- … and {len(lines) - kept} more (call recall)\n" if kept < len(lines) else ""
    return "\n\nWhat you remember (from the memory tools):\n" + text + more
