"""Run one device instance over HTTP on loopback, the way ``rosaos up`` serves it, for tests.

The server runs on an event loop in a background thread, so a class-scoped server works with
any pytest-asyncio loop scope (or none): tests reach it only over HTTP, as a worker would.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import secrets
import threading
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from importlib.metadata import entry_points
from pathlib import Path
from types import ModuleType
from typing import Any

import httpx
from fastmcp import Client
from pydantic import BaseModel, ValidationError

from rosaos.config import format_validation_error
from rosaos.devices.serve import open_device, serve_http
from rosaos.devices.world import DeviceInstance
from rosaos.drivers import DriverSpec
from rosaos.hookspecs import ENTRY_POINT_GROUP
from rosaos.plugins import DriverInfo, DriverRegistry, load_drivers

START_TIMEOUT = 30.0
"""Seconds a device server may take to start (a simulator subprocess, say) before the kit gives up."""


@dataclass(frozen=True)
class RunningDevice:
    """A device instance served over streamable HTTP on loopback, behind a bearer token."""

    instance: DeviceInstance
    url: str
    token: str
    simulated: bool
    """What the started backend says about itself (``DeviceBackend.simulated``)."""

    def client(self) -> Client[Any]:
        """A FastMCP client for this device; use it as ``async with device.client() as client:``."""
        return Client(self.url, auth=self.token)


def load_all_drivers(extra_plugins: Mapping[str, ModuleType] | None = None) -> DriverRegistry:
    """Every installed driver plugin, whatever ``ROSAOS_DRIVERS`` says in the developer's shell."""
    everything = {ep.name for ep in entry_points(group=ENTRY_POINT_GROUP)} | set(extra_plugins or {})
    return load_drivers(allow=everything, extra_plugins=dict(extra_plugins or {}))


def build_instance(
    info: DriverInfo,
    name: str,
    *,
    description: str | None = None,
    settings: Mapping[str, Any] | None = None,
    sim: Mapping[str, Any] | None = None,
) -> DeviceInstance:
    """A ``sim`` instance of ``info``'s driver, with settings validated like ``rosaos.toml`` would be.

    Raises ``ValueError`` naming the bad setting when ``settings`` does not fit the driver's model.
    """
    spec = info.spec
    return DeviceInstance(
        name=name,
        driver=info,
        backend="sim",
        description=description or spec.description,
        settings=validate_settings(spec, name, settings),
        sim=dict(sim or {}),
    )


def validate_settings(spec: DriverSpec, name: str, settings: Mapping[str, Any] | None) -> BaseModel:
    """``settings`` validated by ``spec.settings``, like ``[devices.NAME]`` in ``rosaos.toml``.

    Raises ``ValueError`` naming the bad setting.
    """
    try:
        return spec.settings.model_validate(dict(settings or {}))
    except ValidationError as error:
        raise ValueError(format_validation_error("settings", error, prefix=f"devices.{name}")) from None


@contextlib.contextmanager
def run_device(instance: DeviceInstance, data_dir: Path, token: str | None = None) -> Iterator[RunningDevice]:
    """Serve ``instance`` over HTTP on 127.0.0.1 (a free port) until the block exits.

    Start-up failures (the backend's :class:`~rosaos.drivers.DeviceError`, a bind error) are
    raised here; so is a failure while closing the backend on exit.
    """
    token = token or secrets.token_urlsafe(24)
    ready = threading.Event()
    outcome: dict[str, Any] = {}

    async def serve() -> None:
        stop = asyncio.Event()
        outcome["stop"] = (asyncio.get_running_loop(), stop)
        async with open_device(instance, data_dir) as opened, serve_http(opened.server, token) as served:
            outcome["device"] = RunningDevice(instance, served.url, token, bool(opened.backend.simulated))
            ready.set()
            await stop.wait()

    def thread_main() -> None:
        try:
            asyncio.run(serve())
        except BaseException as error:  # handed to the test thread, which raises it
            outcome["error"] = error
        finally:
            ready.set()

    thread = threading.Thread(target=thread_main, name=f"rosaos-device-{instance.name}", daemon=True)
    thread.start()
    if not ready.wait(START_TIMEOUT):
        raise TimeoutError(f"{instance.name}: the device server did not start within {START_TIMEOUT:.0f}s")
    if "device" not in outcome:
        thread.join()
        raise outcome.get("error") or RuntimeError(f"{instance.name}: the device server stopped at start-up")
    try:
        yield outcome["device"]
    finally:
        loop, stop = outcome["stop"]
        with contextlib.suppress(RuntimeError):  # the loop already ended: nothing to stop
            loop.call_soon_threadsafe(stop.set)
        thread.join(START_TIMEOUT)
        if "error" in outcome:
            raise outcome["error"]


async def raw_tool_call(
    device: RunningDevice, tool: str, args: dict[str, Any], timeout: float
) -> dict[str, Any]:
    """Call ``tool`` with ``args`` written by :func:`json.dumps`, so NaN and Infinity reach the server.

    An MCP client writes a NaN as ``null`` (pydantic's JSON), which hides what a careless caller
    really sends. Returns the JSON-RPC ``result`` (``isError`` and ``content``); raises
    ``TimeoutError`` when no answer comes within ``timeout`` seconds."""
    version = "2026-07-28"
    body = {
        "jsonrpc": "2.0",
        "id": 1,
        "method": "tools/call",
        "params": {
            "name": tool,
            "arguments": args,
            "_meta": {
                "io.modelcontextprotocol/protocolVersion": version,
                "io.modelcontextprotocol/clientCapabilities": {},
            },
        },
    }
    headers = {
        "Authorization": f"Bearer {device.token}",
        "Accept": "application/json, text/event-stream",
        "Content-Type": "application/json",
        "mcp-protocol-version": version,
        "mcp-method": "tools/call",
        "mcp-name": tool,
    }
    async with httpx.AsyncClient(timeout=timeout) as http:
        try:
            response = await http.post(device.url, content=json.dumps(body), headers=headers)
        except httpx.TimeoutException:
            raise TimeoutError(f"{tool} did not answer within {timeout:g} s") from None
    text = response.text
    if "text/event-stream" in response.headers.get("content-type", ""):
        data = [line[5:].strip() for line in text.splitlines() if line.startswith("data:")]
        text = data[-1] if data else "{}"
    answer = json.loads(text)
    if "result" in answer:
        return dict(answer["result"])
    return {"isError": True, "content": [{"type": "text", "text": json.dumps(answer.get("error"))}]}
