"""The paper's demonstration as an LLM would play it, scripted with ``FunctionModel`` (no LLM).

Workers import this module in their own subprocess as ``python:paper_scripts:process_model``.

The kernel script understands the two requests of the rosaOS paper (section 6) the way the kernel
prompt asks an LLM to: the search is launched alone on the TurtleBot with the lamp as its
follow-up (``launch_process(..., then=...)``); the follow-up is launched from the search's
``[Process callback]`` only when it found someone. The process script plays a process agent that
reads its task and calls its granted device's tools.
"""

from __future__ import annotations

import json
import re
from typing import Any

from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    TextPart,
    ToolCallPart,
    ToolReturnPart,
    UserPromptPart,
)
from pydantic_ai.models.function import AgentInfo, FunctionModel

SEARCH_REQUEST = "undock the TurtleBot, search the environment for a person, and when someone is found, turn the lamp green"
SECOND_REQUEST = "make the PuppyPi walk forward and play a song on Spotify"


def _last_user_text(messages: list[ModelMessage]) -> str:
    for message in reversed(messages):
        if isinstance(message, ModelRequest):
            for part in message.parts:
                if isinstance(part, UserPromptPart) and isinstance(part.content, str):
                    return part.content
    return ""


def _callback(body: str) -> dict[str, Any]:
    """The fields of a ``[Process callback]`` as an LLM reads them: the head, output or error, then."""
    head, *lines = body.splitlines()
    fields: dict[str, Any] = dict(re.findall(r"\b(process|status)=(\S+)", head))
    then = re.search(r" then=(['\"])(?P<then>.*)\1$", head)
    fields["then"] = then["then"] if then else None
    for line in lines:
        key, _, value = line.partition(": ")
        if key in ("output", "error"):
            fields[key] = json.loads(value)
    return fields


def _returns(messages: list[ModelMessage]) -> list[ToolReturnPart]:
    last = messages[-1]
    if not isinstance(last, ModelRequest):
        return []
    return [part for part in last.parts if isinstance(part, ToolReturnPart)]


def _events(prompt: str) -> list[str]:
    """The events of one kernel prompt, each from its "[Kind ...]" header line to the next."""
    events: list[str] = []
    for line in prompt.splitlines():
        if (line.startswith("[") and "] " in line) or not events:
            events.append(line)
        else:
            events[-1] += "\n" + line
    return [event.strip() for event in events]


def _answer(event: str) -> str | list[ToolCallPart]:
    """What the kernel does about one event: the launches it makes, or the words it says."""
    tag, _, body = event.partition("] ")
    if tag == "[User said" and body.strip().lower() == SEARCH_REQUEST.lower():
        launch = {
            "task": "Undock, then search the environment for a person and report whether you found one.",
            "devices": ["turtlebot"],
            "then": "Turn the lamp green.",
        }
        return [ToolCallPart("launch_process", launch)]
    if tag == "[User said" and body.strip().lower() == SECOND_REQUEST.lower():
        return [
            ToolCallPart("launch_process", {"task": "Walk forward half a meter.", "devices": ["dog"]}),
            ToolCallPart("launch_process", {"task": "Play Here Comes the Sun.", "devices": ["spotify"]}),
        ]
    if tag == "[Process callback":
        callback = _callback(body)
        follow_up, output = callback["then"], callback.get("output") or ""
        if follow_up is None:
            return f"process {callback['process']}: {output}"
        if callback["status"] == "ok" and output.startswith("Found"):
            return [ToolCallPart("launch_process", {"task": follow_up, "devices": ["lamp"]})]
        return f"{output or callback.get('error')} So I did not: {follow_up}"
    return f"Noted: {event[:80]}"


def kernel_model() -> FunctionModel:
    """The kernel, as an LLM following the kernel prompt would act."""

    async def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        assert (
            "then"
            in next(t for t in info.function_tools if t.name == "launch_process").parameters_json_schema[
                "properties"
            ]
        )
        returns = _returns(messages)
        if returns:
            return ModelResponse(parts=[TextPart("; ".join(str(part.content) for part in returns))])
        # Events that arrived while the model was busy come in one prompt (the kernel batches
        # them, as it does for an LLM): under load the search's "person_seen" notice and its
        # callback share a turn, and the callback must still launch the lamp.
        calls: list[ToolCallPart] = []
        said: list[str] = []
        for event in _events(_last_user_text(messages)):
            answer = _answer(event)
            if isinstance(answer, str):
                said.append(answer)
            else:
                calls += answer
        if calls:
            return ModelResponse(parts=calls)
        return ModelResponse(parts=[TextPart(" ".join(said))])

    return FunctionModel(respond, model_name="paper-kernel")


def _tool(info: AgentInfo, name: str) -> str:
    for tool in info.function_tools:
        if tool.name == name or tool.name.endswith(f"_{name}"):
            return tool.name
    raise AssertionError(f"no tool {name!r} among {[t.name for t in info.function_tools]}")


def _result(part: ToolReturnPart) -> dict[str, Any]:
    content = part.content
    if isinstance(content, str):
        try:
            content = json.loads(content)
        except ValueError:
            return {}
    return content if isinstance(content, dict) else {}


def process_model() -> FunctionModel:
    """A process agent: the tool calls its task asks for, in order, then one sentence."""

    async def respond(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        # The task section of the system prompt only: device prompts mention other tools.
        _, _, after = (info.instructions or "").partition("# Your task\n")
        task = after.partition("\n\n#")[0].lower()
        if "search" in task:
            plan: list[tuple[str, dict[str, Any]]] = [("undock", {}), ("search", {"target": "person"})]
        elif "lamp green" in task:
            plan = [("set_color_name", {"name": "green"})]
        elif "walk forward" in task:
            plan = [("move_distance", {"meters": 0.5})]
        elif "play" in task:
            plan = [("play", {"query": "Here Comes the Sun"})]
        else:
            return ModelResponse(parts=[TextPart("I do not know this task.")])
        returns = [
            p
            for m in messages
            if isinstance(m, ModelRequest)
            for p in m.parts
            if isinstance(p, ToolReturnPart)
        ]
        if len(returns) < len(plan):
            name, args = plan[len(returns)]
            return ModelResponse(parts=[ToolCallPart(_tool(info, name), args)])
        last = _result(returns[-1])
        if "found" in last:
            if last["found"]:
                return ModelResponse(
                    parts=[TextPart(f"Found a person at ({last.get('x')}, {last.get('y')}).")]
                )
            return ModelResponse(parts=[TextPart("I searched but found no one.")])
        return ModelResponse(parts=[TextPart("Done.")])

    return FunctionModel(respond, model_name="paper-process")
