"""Test helpers: a Reachy Mini on the SDK's simulated daemon, and a fake OpenAI-compatible service.

Starting the daemon takes seconds, so test modules share one robot (module-scoped, on a
module-scoped event loop) and open a fresh in-memory MCP client per test.
"""

from __future__ import annotations

import contextlib
import io
import json
import threading
import wave
from collections.abc import AsyncIterator, Iterator
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

from fastmcp import Client, FastMCP

from rosaos.drivers import DeviceContext
from rosaos_reachy.backend import ReachyBackend
from rosaos_reachy.plugin import sim_backend
from rosaos_reachy.server import build_server
from rosaos_reachy.settings import ReachySettings

FIXTURES = Path(__file__).parent / "fixtures"
FACE_PHOTO = FIXTURES / "astronaut.jpg"
"""A public-domain NASA portrait (see fixtures/README.md): a real face for OpenCV's detector."""
BENCH_STATE = {
    "head": {"roll": 0, "pitch": 0, "yaw": 0},
    "antennas": [0, 0],
    "body_yaw": 0,
    "awake": True,
    "last_spoken": "",
}
"""The initial Reachy state of the public bench worlds (robots.yaml, multi.yaml)."""
CLOUD_KEYS = ("ELEVENLABS_API_KEY", "GROQ_API_KEY", "OPENAI_API_KEY")


def sim_context(data_dir: Path, settings: dict[str, Any] | None = None, **sim: Any) -> DeviceContext:
    """The context the hosting layer builds for a ``sim`` reachy instance."""
    return DeviceContext(
        instance="reachy",
        description="Reachy Mini desktop robot, the user's companion on the desk",
        settings=ReachySettings.model_validate({"audio_output": "file", **(settings or {})}),
        backend="sim",
        sim=sim,
        data_dir=data_dir,
    )


@dataclass
class Robot:
    """A started simulated Reachy Mini and its MCP server."""

    backend: ReachyBackend
    server: FastMCP
    ctx: DeviceContext

    @contextlib.asynccontextmanager
    async def client(self) -> AsyncIterator[Client[Any]]:
        async with Client(self.server) as client:
            yield client

    async def call(self, tool: str, **args: Any) -> Any:
        """Call a tool; its structured result (or text)."""
        async with self.client() as client:
            result = await client.call_tool(tool, args)
        if result.structured_content is not None:
            return result.structured_content.get("result", result.structured_content)
        return " ".join(getattr(block, "text", "") for block in result.content)

    async def error(self, tool: str, **args: Any) -> str:
        """Call a tool that must fail; the error text the model would read."""
        async with self.client() as client:
            result = await client.call_tool(tool, args, raise_on_error=False)
        assert result.is_error, f"{tool}({args}) should have failed"
        return " ".join(getattr(block, "text", "") for block in result.content)


@contextlib.asynccontextmanager
async def running_robot(ctx: DeviceContext) -> AsyncIterator[Robot]:
    """Start the sim backend (and so the daemon), yield it with its server, close it."""
    backend = sim_backend(ctx)
    try:
        await backend.start()
        yield Robot(backend, build_server(ctx, backend), ctx)
    finally:
        await backend.close()


# --- a fake OpenAI-compatible service on loopback ------------------------------------------------


def tone_wav(seconds: float = 0.5, rate: int = 16000) -> bytes:
    """A silent WAV file of ``seconds``."""
    buffer = io.BytesIO()
    with wave.open(buffer, "wb") as out:
        out.setnchannels(1)
        out.setsampwidth(2)
        out.setframerate(rate)
        out.writeframes(b"\x00\x00" * int(seconds * rate))
    return buffer.getvalue()


@dataclass
class FakeOpenAI:
    """Records requests; answers chat completions and speech like an OpenAI-compatible server."""

    url: str = ""
    requests: list[dict[str, Any]] = field(default_factory=list)
    answer: str = "A woman in an orange space suit smiles in front of a flag."
    fail_with: int | None = None


@contextlib.contextmanager
def serve_fake_openai() -> Iterator[FakeOpenAI]:
    """A loopback HTTP server at ``fake.url`` (…/v1) speaking the OpenAI chat and speech APIs."""
    fake = FakeOpenAI()

    class Handler(BaseHTTPRequestHandler):
        def do_POST(self) -> None:
            body = json.loads(self.rfile.read(int(self.headers.get("Content-Length", 0))) or b"{}")
            fake.requests.append({"path": self.path, "headers": dict(self.headers), "body": body})
            if fake.fail_with is not None:
                self._send(fake.fail_with, b'{"error": {"message": "overloaded"}}', "application/json")
            elif self.path.endswith("/chat/completions"):
                reply = {"choices": [{"message": {"role": "assistant", "content": fake.answer}}]}
                self._send(200, json.dumps(reply).encode(), "application/json")
            elif self.path.endswith("/audio/speech"):
                self._send(200, tone_wav(0.75), "audio/wav")
            else:
                self._send(404, b"{}", "application/json")

        def _send(self, status: int, data: bytes, kind: str) -> None:
            self.send_response(status)
            self.send_header("Content-Type", kind)
            self.send_header("Content-Length", str(len(data)))
            self.end_headers()
            self.wfile.write(data)

        def log_message(self, *args: Any) -> None:  # keep test output quiet
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    fake.url = f"http://127.0.0.1:{server.server_address[1]}/v1"
    try:
        yield fake
    finally:
        server.shutdown()
        server.server_close()
