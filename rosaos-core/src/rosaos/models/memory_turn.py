"""The offline kernel model's memory turns: places, facts and aliases, without an LLM.

:class:`rosaos.models.kernel_model.LocalIntentModel` asks :func:`memory_turn` after the timers.
It answers user text that is a memory request (:mod:`rosaos.memory.memory_phrases`) with one call to
a memory tool (:mod:`rosaos.memory.memory_tools`), and those tools' results with one sentence. The
``go_to_place`` process's callback is a planned process's like any other: its plan words it.
Anything else is left to the engine (None).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from pydantic_ai.messages import ModelMessage, ModelResponsePart, TextPart, ToolCallPart

from rosaos.events.plan import result_data
from rosaos.intents.understanding.match_result import MatchResult
from rosaos.memory.memory_phrases import (
    MEMORY_TOOL_NAMES,
    Forget,
    ForgetPlace,
    ForgetSightings,
    GoToPlace,
    ListPlaces,
    MemoryRequest,
    Recall,
    RecallSightings,
    RememberNote,
    RememberPlace,
    ShowSighting,
    UnknownPlace,
    read_memory_request,
    resolve_aliases,
)
from rosaos.memory.store import MemoryStore
from rosaos.models.conversation import (
    ToolOutcome,
    content_text,
    current_turn,
    said,
    tool_outcomes,
    turn_event,
)
from rosaos.models.turn_outcome import marked

Match = Callable[[str], MatchResult]


def memory_request(text: str, store: MemoryStore, match: Match) -> MemoryRequest | None:
    """The memory request in ``text`` (aliases resolved), or None; "go to X" for an unknown X, and
    a fact or alias, only when the engine does not understand the sentence otherwise."""
    said = resolve_aliases(text, store.aliases())
    request = read_memory_request(said, {place.key for place in store.places()})
    # "Go to sleep", "call the turtlebot back": a command the engine understands wins over a
    # reading as an unknown place or an alias.
    if isinstance(request, UnknownPlace | RememberNote) and match(said).kind in ("plans", "clarify"):
        return None
    return request


def memory_turn(
    messages: Sequence[ModelMessage], tools: Sequence[str], store: MemoryStore | None, match: Match
) -> list[ModelResponsePart] | None:
    """The response parts when this turn is about memory, else None (see the module docstring)."""
    if store is None:
        return None
    turn = current_turn(messages)
    outcomes = tool_outcomes(turn)
    if outcomes:
        mine = [o for o in outcomes if _base(o.call.tool_name) in MEMORY_TOOL_NAMES]
        return [TextPart(" ".join(_reply(o) for o in mine))] if mine else None
    text = said(turn_event(messages))
    if text is None:
        return None
    request = memory_request(text, store, match)
    if request is None:
        return None
    return _calls(request, text, tools, store)


def _calls(
    request: MemoryRequest, said: str, tools: Sequence[str], store: MemoryStore
) -> list[ModelResponsePart]:
    if isinstance(request, UnknownPlace):
        known = ", ".join(place.name for place in store.places())
        return [marked(f"I don't know a place called {request.name}. I know: {known}.", "refused")]
    if isinstance(request, RememberPlace):
        args: dict[str, Any] = {"name": request.name}
        if request.x is not None:
            args |= {"x": request.x, "y": request.y}
        if request.yaw is not None:
            args["yaw"] = request.yaw
        if request.robot:
            args["device"] = _instance(request.robot)
        return _call(tools, "remember_place", args)
    if isinstance(request, GoToPlace):
        device = {"device": _instance(request.robot)} if request.robot else {}
        return _call(tools, "go_to_place", {"name": request.name} | device)
    if isinstance(request, ListPlaces):
        return _call(tools, "list_places", {})
    if isinstance(request, ForgetPlace):
        return _call(tools, "forget_place", {"name": request.name})
    if isinstance(request, RememberNote):
        args = {"kind": request.kind, "key": request.key, "value": request.value, "said": said.strip()}
        return _call(tools, "remember", args)
    if isinstance(request, RecallSightings):
        args = {"place": request.place, "today": request.today} if request.place else {}
        return _call(tools, "recall_sightings", args)
    if isinstance(request, ForgetSightings):
        return _call(tools, "forget_sightings", {})
    if isinstance(request, ShowSighting):
        return _call(tools, "show_sighting", {})
    if isinstance(request, Recall):
        return _call(tools, "recall", {"about": request.about} if request.about else {})
    assert isinstance(request, Forget)
    return _call(tools, "forget", {"matching": request.matching})


def _instance(robot: str) -> str:
    """The instance name a robot was called by ("the dog" → ``dog``)."""
    return robot.removeprefix("the ").removeprefix("my ").replace(" ", "_")


def _call(tools: Sequence[str], name: str, args: dict[str, Any]) -> list[ModelResponsePart]:
    tool = next((tool for tool in tools if _base(tool) == name), None)
    if tool is None:  # an agent built without the memory tools (a test, an old config): say so
        return [TextPart(f"Memory is not available here (no {name} tool).")]
    return [ToolCallPart(tool, args)]


def _base(tool: str) -> str:
    return next((name for name in MEMORY_TOOL_NAMES if tool == name or tool.endswith("_" + name)), tool)


def _reply(outcome: ToolOutcome) -> str:
    tool, args = _base(outcome.call.tool_name), outcome.call.args_as_dict()
    if not outcome.ok:
        return f"I couldn't do that: {content_text(outcome.content)}"
    result = result_data(outcome.content)
    if isinstance(result, dict) and set(result) == {"result"}:
        result = result["result"]
    if tool == "remember_place" and isinstance(result, dict):
        where = f"x {result['x']:.2f}, y {result['y']:.2f}"
        return f"Saved {result['name']} ({where} on the {result['device']}'s {result['frame']} frame)."
    if tool == "go_to_place":
        return f"On my way to {args.get('name', 'the place')}."
    if tool == "list_places" and isinstance(result, list):
        if not result:
            return "I don't know any places yet. Stand a robot somewhere and say 'remember this spot as the kitchen'."
        names = ", ".join(f"{p['name']} ({p['device']})" for p in result)
        return f"I know {len(result)} place{'s' if len(result) != 1 else ''}: {names}."
    if tool == "forget_place" and isinstance(result, dict):
        return f"Forgotten: {result['name']}."
    if tool == "remember" and isinstance(result, dict):
        if result["kind"] == "alias":
            return f"OK, {result['key'].title()} is {result['value']}."
        return f"I'll remember that: {result['said']}."
    if tool == "recall" and isinstance(result, dict):
        return _recalled(result)
    if tool == "recall_sightings" and isinstance(result, dict):
        return _seen(result["sightings"], args, result.get("kept_days", 7))
    if tool == "show_sighting" and isinstance(result, dict):
        seen = f"{result['what']} {_where(result)}, {result['ago']}, seen by the {result['device']}"
        return f"Here is the picture of the {seen}: {result['picture']} (on the page)."
    if tool == "forget_sightings" and isinstance(result, dict):
        return f"Forgotten: {result['forgotten']} sightings."
    if tool == "forget" and isinstance(result, list):
        return "Forgotten: " + "; ".join(note["said"] for note in result) + "."
    return content_text(outcome.content)


def _seen(sightings: list[dict[str, Any]], args: dict[str, Any], kept_days: float) -> str:
    place = args.get("place")
    when = " today" if args.get("today") else f" in the last {kept_days:g} days"
    if not sightings:
        return f"No, nobody was seen in {place}{when}." if place else f"I haven't seen anyone{when}."
    last = sightings[0]
    seen = f"{_where(last)}, {last['ago']}, seen by the {last['device']}"
    if place:
        more = f" ({len(sightings)} times)" if len(sightings) > 1 else ""
        return f"Yes: last {seen}{more}."
    return seen[0].upper() + seen[1:] + "."


def _where(sighting: dict[str, Any]) -> str:
    if sighting.get("place"):
        return f"in {sighting['place']}"
    if sighting.get("frame") == "fixed":  # a face the Reachy saw: where the Reachy stands
        return f"in front of the {sighting['device']}"
    if sighting.get("x") is not None:
        return f"at x {sighting['x']:.1f}, y {sighting['y']:.1f} ({sighting.get('frame') or 'odom'} frame)"
    return "somewhere I can't place"


def _recalled(result: dict[str, Any]) -> str:
    notes, places = result.get("notes", []), result.get("places", [])
    if not notes and not places:
        return "I don't remember anything about that yet."
    parts = [note["said"] for note in notes]
    if places:
        parts.append("places: " + ", ".join(p["name"] for p in places))
    return "I remember: " + "; ".join(parts) + "."


def is_memory_sentence(text: str, store: MemoryStore | None, match: Match) -> bool:
    """Whether ``text`` is a memory request the engine answers (for prefer_local routing)."""
    return store is not None and memory_request(text, store, match) is not None
