"""A scripted OpenAI-compatible chat server for the LLM-path benchmark: it plays an LLM, on loopback.

It answers ``POST /v1/chat/completions`` the way a model following rosaOS's prompts would, from a
fixed script (no model, no network beyond loopback), and logs every request: its bytes, an
estimate of its tokens (bytes / 4), whether the kernel or a process agent sent it, and the tools
it offered. Before answering it sleeps as a real model would (:class:`Latency`), so the time from
``POST /chat`` to the device changing includes what the model's prefill and decoding would cost.

The script reads what it is sent, not rosaOS's internals: a kernel request is one that offers
``launch_process``. On a user's sentence the kernel launches the processes of :data:`COMMANDS`, with
"On it." beside the calls (as the kernel prompt asks); after its launches it acknowledges them (if
rosaOS asks it to); on a process's callback it answers in one sentence, or launches the follow-up
the paper's demo asks for. A process agent calls the tools its task needs (:data:`PLANS`), one per
request, with "Done." beside the call that finishes the task when that call's success says it
all (as the process prompt asks since issue 22's fourth sitting; before, a sentence restating the
task), and a one-sentence report after the results otherwise.
rosaOS at 4416b49 ignored text beside tool calls and asked again; the script is the same for both.
"""

from __future__ import annotations

import json
import re
import threading
import time
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

DEMO_SENTENCE = "undock the TurtleBot, search the environment for a person, and when someone is found, turn the lamp green"
LAUNCH = "launch_process"

COMMANDS: dict[str, list[dict[str, Any]]] = {
    # The user's sentence is the whole task: as launch_process's schema says, the task is left out
    # and the process gets the sentence as said (issue 22, fourth sitting; before, the kernel
    # copied it: "Turn on the kitchen light.").
    "turn on the kitchen light": [{"devices": ["kitchen_light"]}],
    "turn off the kitchen light": [{"devices": ["kitchen_light"]}],
    "turn on the living room lamp": [{"devices": ["living_room_lamp"]}],
    "turn off the living room lamp": [{"devices": ["living_room_lamp"]}],
    "make the living room lamp blue": [{"devices": ["living_room_lamp"]}],
    "play some jazz": [{"devices": ["spotify"]}],
    "pause the music": [{"devices": ["spotify"]}],
    DEMO_SENTENCE: [
        {
            "task": "Undock, then search the environment for a person and report whether you found one.",
            "devices": ["turtlebot"],
            "then": "Turn the living room lamp green.",
        }
    ],
}
"""What the scripted kernel launches for each sentence it knows."""

PLANS: list[tuple[str, list[tuple[str, dict[str, Any]]]]] = [
    ("search", [("undock", {}), ("search", {"target": "person", "max_seconds": 60})]),
    ("green", [("set_color_name", {"name": "green"})]),
    ("blue", [("set_color_name", {"name": "blue"})]),
    ("turn on", [("turn_on", {})]),
    ("turn off", [("turn_off", {})]),
    ("play", [("play", {"query": "jazz"})]),
    ("pause", [("pause", {})]),
]
"""The tool calls a process agent makes for a task containing each key (first match wins)."""


@dataclass(frozen=True)
class Latency:
    """Seconds a request costs: ``base`` + per prompt token + per output token.

    With ``prefix_cache`` (llama.cpp's ``cache_prompt``, vLLM's and Ollama's prefix caching) only
    the prompt tokens after the longest prefix shared with the last request of the same agent
    (kernel or process) are prefilled; the issue's profiles charge every prompt token.
    """

    name: str
    base: float
    per_prompt_token: float
    per_output_token: float
    prefix_cache: bool = False

    def seconds(self, prompt_tokens: int, output_tokens: int) -> float:
        return self.base + self.per_prompt_token * prompt_tokens + self.per_output_token * output_tokens


PROFILES = {
    "none": Latency("none", 0.0, 0.0, 0.0),
    "cloud": Latency("cloud", 0.4, 0.0002, 0.010),
    "local-8b": Latency("local-8b", 0.0, 0.0005, 0.025),
    "local-8b-cached": Latency("local-8b-cached", 0.0, 0.0005, 0.025, prefix_cache=True),
}


def templated(body: dict[str, Any]) -> str:
    """The prompt as a chat template lays it out: the tools first, then the messages in order."""
    return json.dumps(body.get("tools", [])) + "".join(json.dumps(m) for m in body.get("messages", []))


def generated_bytes(message: dict[str, Any]) -> int:
    """What a model writes for ``message``: its text, and per tool call the name, the arguments
    and a ~24-byte call wrapper (``<tool_call>{"name": …, "arguments": …}</tool_call>``). The
    call id and the JSON envelope are the server's, not decoded tokens."""
    calls = message.get("tool_calls") or []
    text = len(message.get("content") or "")
    return text + sum(len(c["function"]["name"]) + len(c["function"]["arguments"]) + 24 for c in calls)


def shared_prefix(a: str, b: str) -> int:
    """Length of the longest common prefix of ``a`` and ``b``."""
    limit = min(len(a), len(b))
    index = 0
    while index < limit and a[index] == b[index]:
        index += 1
    return index


@dataclass(frozen=True)
class Logged:
    """One request the server answered."""

    role: str
    """``kernel`` or ``process``."""
    bytes: int
    prompt_tokens: int
    output_tokens: int
    tools: int
    tool_bytes: int
    at: float
    """``time.time()`` when the answer was sent."""
    prefilled_tokens: int = 0
    """Prompt tokens charged: all of them, or with a prefix cache those after the cached prefix."""
    seconds: float = 0.0
    """The latency the profile charged for this request."""
    system_bytes: int = 0


@dataclass
class Script:
    """The server's state: the latency profile and the log."""

    latency: Latency = PROFILES["none"]
    log: list[Logged] = field(default_factory=list)
    cached: dict[str, str] = field(default_factory=dict)
    """Per agent role, the last prompt (as templated), for the prefix-cache profile."""
    dump: str | None = None
    """A directory to write every request body to (``NNN-role.json``), to see where bytes go."""
    lock: threading.Lock = field(default_factory=threading.Lock)

    def reset(self, latency: Latency) -> None:
        with self.lock:
            self.latency, self.log = latency, []


def _text(content: Any) -> str:
    if isinstance(content, str):
        return content
    if isinstance(content, list):
        return " ".join(str(item.get("text", "")) for item in content if isinstance(item, dict))
    return ""


def _tool_names(body: dict[str, Any]) -> list[str]:
    return [tool["function"]["name"] for tool in body.get("tools", []) if "function" in tool]


def _call(name: str, args: dict[str, Any], index: int) -> dict[str, Any]:
    return {
        "id": f"call_{index}_{int(time.time() * 1000) % 100000}",
        "type": "function",
        "function": {"name": name, "arguments": json.dumps(args)},
    }


def _current_turn(messages: list[dict[str, Any]]) -> list[dict[str, Any]]:
    for index in range(len(messages) - 1, -1, -1):
        if messages[index].get("role") == "user":
            return messages[index:]
    return messages


def kernel_answer(messages: list[dict[str, Any]]) -> dict[str, Any]:
    """The scripted kernel's answer to a request whose messages are ``messages``."""
    turn = _current_turn(messages)
    if turn[-1].get("role") == "tool":  # its launches came back: acknowledge
        return {"role": "assistant", "content": "On it."}
    event = _text(turn[0].get("content")) if turn else ""
    lowered = event.lower()
    if "callback" in lowered:
        follow_up = re.search(r"Kernel follow-up[^:]*:\s*(?P<then>[^\n\"'\\]+)", event)
        if (
            follow_up
            and "status=ok" in event.replace('"status": "ok"', "status=ok")
            and "found a person" in lowered
        ):
            task = follow_up.group("then").strip()
            launch = {"task": task, "devices": ["living_room_lamp"]}
            return {"role": "assistant", "content": None, "tool_calls": [_call(LAUNCH, launch, 0)]}
        return {"role": "assistant", "content": "Done."}
    for sentence, launches in sorted(COMMANDS.items(), key=lambda item: -len(item[0])):
        if sentence.lower() in lowered:
            calls = [_call(LAUNCH, launch, index) for index, launch in enumerate(launches)]
            # As the kernel prompt asks: the words for the user beside the launch.
            return {"role": "assistant", "content": "On it.", "tool_calls": calls}
    return {"role": "assistant", "content": "I did not understand that."}


def process_answer(messages: list[dict[str, Any]], tools: list[str]) -> dict[str, Any]:
    """The scripted process agent's answer: its plan's next tool call, or its report."""
    task = next((_text(m.get("content")) for m in messages if m.get("role") == "user"), "").lower()
    plan = next((steps for key, steps in PLANS if key in task), [])
    results = [m for m in messages if m.get("role") == "tool"]
    if len(results) < len(plan):
        name, args = plan[len(results)]
        tool = next((t for t in tools if t == name or t.endswith(f"_{name}")), None)
        if tool is not None:
            # As the process prompt asks: "Done." beside the call that finishes the task, when the
            # call's success says it all (a search's report depends on what it found).
            last = len(results) == len(plan) - 1 and name != "search"
            report = "Done." if last else None
            return {"role": "assistant", "content": report, "tool_calls": [_call(tool, args, len(results))]}
    last = _text(results[-1].get("content")) if results else ""
    if '"found": true' in last or '"found":true' in last:
        return {"role": "assistant", "content": "Found a person."}
    if '"found"' in last:
        return {"role": "assistant", "content": "I searched but found no one."}
    return {"role": "assistant", "content": "Done."}


class _Handler(BaseHTTPRequestHandler):
    script: Script

    def log_message(self, format: str, *args: Any) -> None:  # quiet
        return

    def do_POST(self) -> None:
        raw = self.rfile.read(int(self.headers.get("Content-Length", "0")))
        body = json.loads(raw)
        tools = _tool_names(body)
        messages = body.get("messages", [])
        role = "kernel" if LAUNCH in tools else "process"
        message = kernel_answer(messages) if role == "kernel" else process_answer(messages, tools)
        prompt_tokens, output_tokens = len(raw) // 4, max(1, generated_bytes(message) // 4)
        latency, prompt = self.script.latency, templated(body)
        prefilled = prompt_tokens
        with self.script.lock:
            if latency.prefix_cache:
                cached = shared_prefix(self.script.cached.get(role, ""), prompt)
                prefilled = max(0, prompt_tokens - cached // 4)
            self.script.cached[role] = prompt
        seconds = latency.seconds(prefilled, output_tokens)
        time.sleep(seconds)
        finish = "tool_calls" if message.get("tool_calls") else "stop"
        reply = {
            "id": "chatcmpl-scripted",
            "object": "chat.completion",
            "created": int(time.time()),
            "model": body.get("model", "scripted"),
            "choices": [{"index": 0, "message": message, "finish_reason": finish}],
            "usage": {
                "prompt_tokens": prompt_tokens,
                "completion_tokens": output_tokens,
                "total_tokens": prompt_tokens + output_tokens,
            },
        }
        data = json.dumps(reply).encode()
        compact = {"separators": (",", ":"), "ensure_ascii": False}  # as the client sends them
        tool_bytes = len(json.dumps(body.get("tools", []), **compact).encode())
        with self.script.lock:
            if self.script.dump:
                path = f"{self.script.dump}/{len(self.script.log):03d}-{role}.json"
                with open(path, "wb") as file:
                    file.write(raw)
            system = sum(
                len(json.dumps(m, **compact).encode()) for m in messages if m.get("role") == "system"
            )
            self.script.log.append(
                Logged(
                    role,
                    len(raw),
                    prompt_tokens,
                    output_tokens,
                    len(tools),
                    tool_bytes,
                    time.time(),
                    prefilled,
                    round(seconds, 3),
                    system,
                )
            )
        self.send_response(200)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.wfile.write(data)


def serve(port: int = 0) -> tuple[ThreadingHTTPServer, Script]:
    """Start the server on loopback in a daemon thread; returns it (``server_address``) and its script."""
    script = Script()
    handler = type("Handler", (_Handler,), {"script": script})
    server = ThreadingHTTPServer(("127.0.0.1", port), handler)
    threading.Thread(target=server.serve_forever, daemon=True, name="scripted-llm").start()
    return server, script
