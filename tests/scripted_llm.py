"""A scripted OpenAI-compatible chat server on loopback, for tests that put an LLM in rosaOS's loop.

It stands in for a cloud or local model (never a paid API): ``POST /v1/chat/completions`` is
answered by a test's :data:`Answer` function from the request's messages, as a model that follows
rosaOS's prompts would. A request that offers ``launch_process`` is the kernel's; any other is a
process agent's. Every request is logged with the status it got, so a test can see what crossed
the wire. ``reject_images`` makes it a text-only model that answers 400 to any image part, as
llama.cpp and vLLM do for a model without a vision tower.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

Message = dict[str, Any]
Answer = Callable[[str, list[Message], list[str]], Message]
"""``(role, messages, tool names) -> assistant message``; role is ``kernel`` or ``process``."""


@dataclass(frozen=True)
class Request:
    """One request the server received, and the HTTP status it answered."""

    role: str
    messages: list[Message]
    tools: list[str]
    status: int

    @property
    def has_image(self) -> bool:
        return any(
            isinstance(m.get("content"), list) and any(p.get("type") == "image_url" for p in m["content"])
            for m in self.messages
        )


@dataclass
class ScriptedLLM:
    """The server's state: how it answers, and what it was asked."""

    answer: Answer
    reject_images: bool = False
    requests: list[Request] = field(default_factory=list)
    lock: threading.Lock = field(default_factory=threading.Lock)
    url: str = ""
    """The ``/v1`` base URL, once serving."""


def text_of(content: Any) -> str:
    """A message's text, whether it is a string or a list of parts."""
    if isinstance(content, str):
        return content
    if isinstance(content, list):
        return " ".join(str(part.get("text", "")) for part in content if isinstance(part, dict))
    return ""


def tool_call(name: str, arguments: dict[str, Any], content: str | None = None) -> Message:
    """An assistant message that calls one tool, with ``content`` beside it."""
    call_id = f"call_{time.monotonic_ns()}"
    call = {"id": call_id, "type": "function", "function": {"name": name, "arguments": json.dumps(arguments)}}
    return {"role": "assistant", "content": content, "tool_calls": [call]}


def say(text: str) -> Message:
    return {"role": "assistant", "content": text}


def tool_results(messages: list[Message]) -> list[str]:
    """The text of every tool result in ``messages``, in order."""
    return [text_of(m.get("content")) for m in messages if m.get("role") == "tool"]


def task_of(messages: list[Message]) -> str:
    """A process agent's task: its first user message."""
    return next((text_of(m.get("content")) for m in messages if m.get("role") == "user"), "")


def _handler(script: ScriptedLLM) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        def log_message(self, format: str, *args: Any) -> None:
            return

        def do_POST(self) -> None:
            body = json.loads(self.rfile.read(int(self.headers.get("Content-Length", "0"))))
            tools = [t["function"]["name"] for t in body.get("tools", []) if "function" in t]
            role = "kernel" if "launch_process" in tools else "process"
            messages = body.get("messages", [])
            request = Request(role, messages, tools, 200)
            if script.reject_images and request.has_image:
                request = Request(role, messages, tools, 400)
                error = {"error": {"message": "image input is not supported by this model", "code": 400}}
                self._send(400, error)
            else:
                message = script.answer(role, messages, tools)
                finish = "tool_calls" if message.get("tool_calls") else "stop"
                self._send(
                    200,
                    {
                        "id": "chatcmpl-scripted",
                        "object": "chat.completion",
                        "created": int(time.time()),
                        "model": body.get("model", "scripted"),
                        "choices": [{"index": 0, "message": message, "finish_reason": finish}],
                        "usage": {"prompt_tokens": 1, "completion_tokens": 1, "total_tokens": 2},
                    },
                )
            with script.lock:
                script.requests.append(request)

        def _send(self, status: int, payload: dict[str, Any]) -> None:
            data = json.dumps(payload).encode()
            self.send_response(status)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

    return Handler


@contextmanager
def scripted_llm(answer: Answer, *, reject_images: bool = False) -> Iterator[ScriptedLLM]:
    """Serve ``answer`` on 127.0.0.1 (a free port) for the duration of the block."""
    script = ScriptedLLM(answer, reject_images)
    server = ThreadingHTTPServer(("127.0.0.1", 0), _handler(script))
    script.url = f"http://127.0.0.1:{server.server_address[1]}/v1"
    thread = threading.Thread(target=server.serve_forever, daemon=True, name="scripted-llm")
    thread.start()
    try:
        yield script
    finally:
        server.shutdown()
        server.server_close()


def models_table(url: str, *, vision: bool | None = None) -> str:
    """The ``[models]`` table that points kernel and processes at the scripted server, model first."""
    table = (
        '\n[models]\nkernel = "openai-compatible"\n'
        f'base_url = "{url}"\nmodel_name = "scripted"\napi_key = "none"\nprefer_local = false\n'
    )
    return table + ("" if vision is None else f"vision = {str(vision).lower()}\n")
