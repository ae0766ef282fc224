"""Helpers for the local-intent engine tests: test worlds, device servers, and the bench task files.

Two test drivers live in ``drivers/``: ``bulb`` (a light, like Tapo) and ``speaker`` (a media
player, like the coming Spotify driver). :func:`build_device_server` gives either one an
in-memory FastMCP server with the tools their intents name, so plans run for real.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

from fastmcp import FastMCP
from fastmcp.exceptions import ToolError
from pydantic import Field

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.vocabulary import DeviceVocabulary, sources_from_config
from rosaos.intents.understanding.matching import IntentMatcher
from rosaos.plugins import load_drivers

INTENTS = Path(__file__).parent / "drivers"
BULB = INTENTS / "bulb.yaml"
SPEAKER = INTENTS / "speaker.yaml"
BENCH_TASKS = Path(__file__).resolve().parents[3].parent / "shared" / "bench" / "tasks"
OWN_TASKS = Path(__file__).resolve().parents[3] / "benchmarks" / "tasks"
"""rosaOS's own task files (everyday variants of the public sentences), in the same format."""


def bulb(name: str, description: str = "", **extra: Any) -> DeviceVocabulary:
    """A light of the test ``bulb`` driver."""
    return DeviceVocabulary(name=name, driver="bulb", description=description, intents=BULB, **extra)


def speaker(name: str = "speaker", description: str = "Music on the desk speaker") -> DeviceVocabulary:
    """A media player of the test ``speaker`` driver."""
    return DeviceVocabulary(name=name, driver="speaker", description=description, intents=SPEAKER)


def home_world() -> list[DeviceVocabulary]:
    """Three lights in three rooms, a speaker, and a device with no intents at all."""
    return [
        bulb("kitchen_light", "Ceiling light in the kitchen", area="cuisine", aliases=("plafonnier",)),
        bulb("living_room_lamp", "Floor lamp in the living room"),
        bulb("bedroom_light", "Bedside light in the bedroom"),
        speaker(),
        DeviceVocabulary(name="turtlebot", driver="ros", description="TurtleBot4 wheeled mobile robot"),
    ]


def build_device_server(name: str, state: dict[str, Any], fail: set[str] | None = None) -> FastMCP:
    """A device server with the test drivers' tools; each returns the state. ``fail`` tools raise."""
    server = FastMCP(name)
    failing = fail or set()

    def act(tool: str, **changes: Any) -> dict[str, Any]:
        if tool in failing:
            raise ToolError(f"{tool} failed: the device is offline")
        state.update(changes)
        state.setdefault("calls", []).append(tool)
        return {key: value for key, value in state.items() if key != "calls"}

    @server.tool
    def get_state() -> dict[str, Any]:
        """Read the state."""
        return act("get_state")

    @server.tool
    def turn_on() -> dict[str, Any]:
        """Turn on."""
        return act("turn_on", on=True)

    @server.tool
    def turn_off() -> dict[str, Any]:
        """Turn off."""
        return act("turn_off", on=False)

    @server.tool
    def set_brightness(brightness: Annotated[int, Field(ge=0, le=100)]) -> dict[str, Any]:
        """Set the brightness."""
        return act("set_brightness", on=True, brightness=brightness)

    @server.tool
    def speak(text: str, voice: str = "default") -> dict[str, Any]:
        """Say something."""
        return act("speak", last_spoken=text)

    @server.tool
    def play(query: str) -> dict[str, Any]:
        """Play music."""
        return act("play", playing=query)

    return server


def plan_calls(result: Any) -> list[tuple[str, str, dict[str, Any]]]:
    """Every step a match planned, as ``(device, tool, args)``, in order: what a spec test compares."""
    return [
        (step.device, step.tool, step.args) for process in result.processes for step in process.plan.steps
    ]


def matcher_for(devices: dict[str, DeviceConfig]) -> IntentMatcher:
    """An English matcher of these devices, with the installed drivers' intents."""
    return IntentMatcher(sources_from_config(devices, load_drivers()), "en")
