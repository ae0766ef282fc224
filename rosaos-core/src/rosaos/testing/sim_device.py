"""A driver's server on its ``sim`` backend, reached through FastMCP's in-memory client: fast tool tests.

::

    from rosaos.testing import open_sim_device

    async def test_dim_lowers_the_brightness() -> None:
        async with open_sim_device(SPEC, "kitchen_light", sim={"brightness": 60}) as bulb:
            assert (await bulb.call("adjust_brightness", change=-25))["brightness"] == 35
            assert "brightness" in await bulb.error("set_brightness", brightness=101)

No HTTP and no token: the client talks to the server object directly, so a test takes
milliseconds. The server is the one ``DriverSpec.server`` builds, without the ``safe_stop`` tool
the host adds when it serves a device; :func:`~rosaos.testing.run_device` serves an instance over
HTTP exactly as ``rosaos up`` does.
"""

from __future__ import annotations

import contextlib
import tempfile
from collections.abc import AsyncIterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fastmcp import Client

from rosaos.drivers import DemoInstance, DeviceBackend, DeviceContext, DriverSpec, NoticeBoard
from rosaos.testing.device_runner import validate_settings


@dataclass
class SimDevice:
    """A started ``sim`` backend and an in-memory FastMCP client on the server built on it."""

    context: DeviceContext
    """What the backend and server factories were given (instance name, settings, ``sim``)."""
    backend: DeviceBackend
    """The backend itself, for checks a tool cannot make (the simulator's inner state)."""
    client: Client[Any]
    """The connected client, for anything beyond :meth:`call` (``list_tools()``, say)."""

    async def call(self, tool: str, **args: Any) -> dict[str, Any]:
        """Call a tool and return its structured result; a tool error raises ``ToolError``."""
        result = await self.client.call_tool(tool, args)
        assert result.structured_content is not None, f"{tool}({args}) returned no structured content"
        return result.structured_content

    async def state(self) -> dict[str, Any]:
        """``get_state``'s answer."""
        return await self.call("get_state")

    async def error(self, tool: str, **args: Any) -> str:
        """Call a tool that must fail and return the error text the model would read."""
        result = await self.client.call_tool(tool, args, raise_on_error=False)
        assert result.is_error, f"{tool}({args}) should have failed: {result.structured_content}"
        return " ".join(getattr(block, "text", "") for block in result.content)


@contextlib.asynccontextmanager
async def open_sim_device(
    spec: DriverSpec,
    instance: str | None = None,
    *,
    sim: Mapping[str, Any] | None = None,
    settings: Mapping[str, Any] | None = None,
    data_dir: Path | None = None,
) -> AsyncIterator[SimDevice]:
    """Start ``spec``'s ``sim`` backend for ``instance``, build the server, and connect a client.

    Defaults come from the demo instance of that name (the driver's first one when ``instance``
    is None), as in the conformance kit: its description, its ``settings``, and its ``sim`` table
    unless ``sim`` is given (``sim={}`` starts the simulator in its own defaults). ``settings`` are
    validated like ``rosaos.toml``'s; ``data_dir`` defaults to a temporary folder removed on exit.
    The backend is closed on exit, also after a failed start.

    Use it inside the test, not in an async fixture: anyio requires the client to be entered and
    left in the same task.
    """
    demo = spec.demo_instances()
    name = instance or next(iter(demo))
    default = demo.get(name) or DemoInstance(description=spec.description)
    with contextlib.ExitStack() as stack:
        if data_dir is None:
            data_dir = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="rosaos-sim-")))
        context = DeviceContext(
            instance=name,
            description=default.description,
            settings=validate_settings(spec, name, default.settings if settings is None else settings),
            backend="sim",
            sim=dict(default.sim if sim is None else sim),
            data_dir=data_dir,
            notices=NoticeBoard(name, spec.name, spec.notices),
        )
        backend = spec.backends["sim"](context)
        try:
            await backend.start()
            server = spec.server(context, backend)
            server.strict_input_validation = True  # as rosaos serves it (devices/serve.py)
            async with Client(server) as client:
                yield SimDevice(context, backend, client)
        finally:
            await backend.close()
