"""The offline kernel model's lease-free turns: "stop", questions about state, "what can you do?".

:class:`rosaos.models.kernel_model.LocalIntentModel` asks :func:`kernel_action_turn` before it
matches a command. It answers:

- a sentence that means stop (:func:`~rosaos.intents.understanding.stop_words.read_stop`) with a
  call to the kernel's ``stop`` tool, and its result with the stop's summary;
- a question about state (:func:`~rosaos.intents.understanding.questions.read_question`) with
  ``device_state`` calls, and their results with the answer, yes or no first. "Does the
  turtlebot see anyone?" on a robot nobody holds launches its driver's look (a fresh picture) as
  a command instead; while a search holds it, the answer comes from what it has seen so far;
- a driver's own question template (a plan that only reads ``get_state``: "how bright is the
  lamp?") with ``device_state`` too, and the template's reply filled from the state;
- "what can you do?" with example sentences built from this world's devices;
- the callback of a process a stop terminated with silence: the stop already said so.

Anything else, or a kernel without these tools, is left to the engine (None).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from typing import Any

from pydantic_ai.messages import ModelMessage, ModelResponsePart, TextPart, ToolCallPart

from rosaos.events.plan import result_data
from rosaos.intents.grammar.state_words import battery, colour, doing, people_seen, position
from rosaos.intents.grammar.vocabulary import DeviceVocabulary
from rosaos.intents.understanding.match_result import MatchResult
from rosaos.intents.understanding.questions import Question, read_question
from rosaos.intents.understanding.small_talk import read_small_talk, small_talk_reply
from rosaos.intents.understanding.stop_words import DeviceRefs, read_stop
from rosaos.models.conversation import (
    ToolOutcome,
    callback_of,
    content_text,
    current_turn,
    said,
    tool_outcomes,
    turn_event,
)
from rosaos.models.process_model import final_reply
from rosaos.notices.notice_plan import SILENCE

STOP_TOOL = "stop"
STATE_TOOL = "device_state"
LAUNCH_TOOL = "launch_process"
MAX_EXAMPLES = 6

Command = Callable[[str, Sequence[str]], list[ModelResponsePart]]
Acknowledge = Callable[[list[ToolOutcome]], str]
Match = Callable[[str], MatchResult]


def kernel_action_turn(
    messages: Sequence[ModelMessage],
    tools: Sequence[str],
    refs: DeviceRefs,
    devices: Sequence[DeviceVocabulary],
    command: Command,
    acknowledge: Acknowledge,
    match: Match,
) -> list[ModelResponsePart] | None:
    """The response parts for a stop, a state question or a callback a stop caused; else None."""
    stop_tool, state_tool = _tool(tools, STOP_TOOL), _tool(tools, STATE_TOOL)
    if stop_tool is None or state_tool is None:
        return None
    event = turn_event(messages)
    outcomes = tool_outcomes(current_turn(messages))
    callback = callback_of(event)
    if callback is not None:
        stopped = callback.status == "terminated" and callback.process_id in _stopped_processes(messages)
        return [TextPart(SILENCE)] if stopped and not outcomes else None
    text = said(event)
    if text is None:
        return None
    stop = read_stop(text, refs)
    question = None if stop is not None else read_question(text, refs)
    if stop is None and question is None:
        chat = read_small_talk(text, lambda word: refs.resolve(word) is not None)
        if chat is not None and not outcomes:  # "hi there, how's it going?": one line, nothing moves
            return [TextPart(small_talk_reply(chat))]
        return _template_question(match(text), outcomes, state_tool)
    if outcomes:
        launched = [outcome for outcome in outcomes if outcome.call.tool_name == _tool(tools, LAUNCH_TOOL)]
        if stop is not None:
            stops = [outcome for outcome in outcomes if outcome.call.tool_name == stop_tool]
            replies = [_stop_reply(stops)]
            if launched:
                replies.append(acknowledge(launched))
            elif stop.rest:  # the rest was not understood, or asked which one: say so
                replies += [part.content for part in command(stop.rest, tools) if isinstance(part, TextPart)]
            return [TextPart(" ".join(replies))]
        if launched:
            return [TextPart(acknowledge(launched))]
        assert question is not None
        return _answer(question, outcomes, text, tools, command)
    if stop is not None:  # the stop first, then the sentence's other commands
        then = (
            [part for part in command(stop.rest, tools) if isinstance(part, ToolCallPart)]
            if stop.rest
            else []
        )
        return [ToolCallPart(stop_tool, {"devices": list(stop.devices)}), *then]
    assert question is not None
    if question.topic == "help":
        return [TextPart(help_text(devices))]
    if not question.devices:
        return [ToolCallPart(state_tool, {})]
    return [ToolCallPart(state_tool, {"device": name}) for name in question.devices]


def _template_question(
    result: MatchResult, outcomes: list[ToolOutcome], state_tool: str
) -> list[ModelResponsePart] | None:
    """A driver's question template ("how bright is the lamp?": plans that only read get_state),
    answered through ``device_state`` instead of a process; None for anything else."""
    if not result.is_exact or not all(
        step.tool == "get_state" for process in result.processes for step in process.plan.steps
    ):
        return None
    plans = [process.plan for process in result.processes]
    if not outcomes:
        return [ToolCallPart(state_tool, {"device": plan.steps[-1].device}) for plan in plans]
    replies = []
    for plan, outcome in zip(plans, outcomes, strict=False):
        data = result_data(outcome.content)
        if not outcome.ok or not isinstance(data, dict) or not isinstance(data.get("state"), dict):
            said = data.get("said") if isinstance(data, dict) else None
            error = " ".join(said) if said else content_text(outcome.content)
            replies.append(plan.failure.replace("{error}", error))
            continue
        replies.append(final_reply(plan, data["state"]))
    return [TextPart(" ".join(replies))]


def handles(text: str, refs: DeviceRefs) -> bool:
    """Whether :func:`kernel_action_turn` answers ``text`` itself (for prefer_local routing)."""
    return (
        read_stop(text, refs) is not None
        or read_question(text, refs) is not None
        or read_small_talk(text, lambda word: refs.resolve(word) is not None) is not None
    )


def _tool(tools: Sequence[str], name: str) -> str | None:
    return next((tool for tool in tools if tool == name), None) or next(
        (tool for tool in tools if tool.endswith(f"_{name}")), None
    )


def _stopped_processes(messages: Sequence[ModelMessage]) -> set[int]:
    """Ids of the processes earlier stops in this conversation terminated."""
    ids: set[int] = set()
    for outcome in tool_outcomes(list(messages)):
        if outcome.ok and outcome.call.tool_name.endswith(STOP_TOOL):
            data = result_data(outcome.content)
            if isinstance(data, dict):
                ids |= {p["id"] for p in data.get("terminated", []) if isinstance(p, dict) and "id" in p}
    return ids


def _stop_reply(outcomes: list[ToolOutcome]) -> str:
    replies = []
    for outcome in outcomes:
        data = result_data(outcome.content)
        if outcome.ok and isinstance(data, dict) and "summary" in data:
            replies.append(str(data["summary"]))
        else:
            replies.append(f"I could not stop that: {content_text(outcome.content)}")
    return " ".join(replies)


def _answer(
    question: Question, outcomes: list[ToolOutcome], said: str, tools: Sequence[str], command: Command
) -> list[ModelResponsePart]:
    readings: list[dict[str, Any]] = []
    for outcome in outcomes:
        data = result_data(outcome.content)
        if not outcome.ok or not isinstance(data, dict):
            return [TextPart(f"I could not read the device: {content_text(outcome.content)}")]
        readings += data.get("devices", [data])
    if question.topic == "people" and not any(reading["held_by"] for reading in readings):
        parts = command(said, tools)  # free: take a fresh look rather than read old sightings
        if any(isinstance(part, ToolCallPart) for part in parts):
            return parts
    answers = [text for reading in readings if (text := _about(question, reading)) is not None]
    if answers:
        return [TextPart(" ".join(answers))]
    names = " or ".join(f"the {_spoken(reading['device'])}" for reading in readings) or "any device"
    return [TextPart(f"{names[0].upper()}{names[1:]} does not report that.")]


def state_answer(question: Question, device: str, state: dict[str, Any]) -> str | None:
    """What the offline kernel answers ``question`` about ``device`` in ``state``, nobody holding
    it (for checks that run no kernel: the bench tasks' plan test)."""
    return _about(question, {"device": device, "state": state, "held_by": []})


def _about(question: Question, reading: dict[str, Any]) -> str | None:
    """One device's answer to ``question``, or None when its state does not say."""
    name, state = _spoken(reading["device"]), reading.get("state")
    the = str(reading.get("called") or f"the {name}")  # "Spotify", not "the spotify" (state_words.called)
    subject = the[:1].upper() + the[1:]
    if not isinstance(state, dict):
        said = reading.get("said") or []
        return str(said[0]) if said and question.devices else None
    topic = question.topic
    if topic in ("on", "off") and isinstance(state.get("on"), bool):
        lit = state["on"]
        yes = lit if topic == "on" else not lit
        level = f", at {state['brightness']}% brightness" if lit and "brightness" in state else ""
        return f"{'Yes' if yes else 'No'}, {the} is {'on' if lit else 'off'}{level}."
    if topic in ("playing", "is_playing") and isinstance(state.get("is_playing"), bool):
        if state["is_playing"] and state.get("track"):
            by = f" by {state['artist']}" if state.get("artist") else ""
            return f"{'Yes: ' if topic == 'is_playing' else ''}{state['track']}{by} is playing on {the}."
        return f"{'No, n' if topic == 'is_playing' else 'N'}othing is playing on {the}."
    if topic == "brightness" and isinstance(state.get("brightness"), int | float):
        off = " (it is off)" if state.get("on") is False else ""
        return f"{subject} is at {state['brightness']}% brightness{off}."
    if topic == "colour" and (shade := colour(state)) is not None:
        off = " (it is off)" if state.get("on") is False else ""
        return f"{subject} is {shade}{off}."
    if topic == "volume" and isinstance(state.get("volume"), int | float):
        return f"{subject}'s volume is at {state['volume']}%."
    if topic == "position" and (where := position(state)) is not None:
        return f"{subject} is {where}."
    if topic == "battery" and (charge := battery(state)) is not None:
        return f"{subject}'s battery is at {charge}."
    if topic == "docked" and isinstance(state.get("docked"), bool):
        if state["docked"]:
            return f"Yes, {the} is docked."
        where = position(state)
        return f"No, {the} is not docked{': it is ' + where if where else ''}."
    if topic == "people" and ("x" in state or "people_seen" in state):
        seen = people_seen(state)
        busy = f" (it is busy: {reading['held_by'][0]['task']})" if reading["held_by"] else ""
        return f"{'Yes' if state.get('people_seen') else 'No'}, {seen}{busy}."
    if topic == "busy":
        if reading["held_by"]:
            return f"Yes, {the} is busy: {reading['held_by'][0]['task']}."
        now = doing(state)
        return f"Yes, {the} is {now}." if now else f"No, {the} is not doing anything."
    return None


def help_text(devices: Sequence[DeviceVocabulary], language: str = "en") -> str:
    """A few things to say, built from this world's devices and their drivers' sentences."""
    examples: list[str] = []
    drivers: set[str] = set()
    for device in devices:
        if device.driver in drivers:  # one per driver: "undock the dog" fits a turtlebot only
            continue
        drivers.add(device.driver)
        example = _example(device, language)
        if example and example not in examples:
            examples.append(example)
        if len(examples) >= MAX_EXAMPLES - 2:
            break
    robot = next((device for device in devices if device.driver in ("ros",)), None)
    examples.append(f"where is the {robot.display_name}?" if robot else "is the light on?")
    examples.append("stop (stops whatever moves, speaks or plays)")
    listed = "; ".join(f"“{example}”" for example in examples)
    return f"You can say, for example: {listed}."


_OPTIONAL = re.compile(r"\[[^\[\]]*\]")
_CHOICE = re.compile(r"\(([^()|]*)(?:\|[^()]*)?\)")


def _example(device: DeviceVocabulary, language: str) -> str | None:
    """The first sentence of the device's driver that names a device, written out for it."""
    intents = device.intents_file(language)
    if intents is None:
        return None
    for intent in intents.hassil.get("intents", {}).values():
        for data in intent.get("data", []):
            for sentence in data.get("sentences", []):
                if "{device}" not in sentence:
                    continue
                text = sentence
                while (reduced := _OPTIONAL.sub("", text)) != text:
                    text = reduced
                while (chosen := _CHOICE.sub(r"\1", text)) != text:
                    text = chosen
                text = text.replace("{device}", f"the {device.display_name}")
                if (
                    "{" in text
                    or "<" in text
                    or "[" in text
                    or "(" in text
                    or device.display_name not in text
                ):
                    continue
                return " ".join(text.split())
    return None


def _spoken(name: str) -> str:
    return name.replace("_", " ")
