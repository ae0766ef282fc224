"""Talk to one device's MCP server: a thin async wrapper over :class:`fastmcp.Client`.

Every failure comes out as a :class:`~rosaos.drivers.DeviceError` whose message says what to do:
nothing listening, token refused, no answer in time, or the tool's own error.

Use it per call (each method opens and closes a session) or as ``async with DeviceClient(...)``
to keep one session for several calls::

    state = await DeviceClient(url, token, timeout=3).get_state()
"""

from __future__ import annotations

import asyncio
import json
from types import TracebackType
from typing import Any

import httpx
import mcp.types
from fastmcp import Client, FastMCP
from fastmcp.exceptions import ToolError
from mcp.shared.exceptions import MCPError

from rosaos.drivers import DeviceError
from rosaos.tls import shared_context

DEFAULT_TIMEOUT = 10.0


class DeviceClient:
    """A client for one device, by URL and bearer token, or for a server object in this process.

    ``name`` (the instance name) only makes error messages say which device failed.
    """

    def __init__(
        self,
        url: str | FastMCP,
        token: str | None = None,
        timeout: float = DEFAULT_TIMEOUT,
        name: str | None = None,
    ) -> None:
        self._client: Client[Any]
        self.url: str
        self.name: str | None
        if isinstance(url, FastMCP):  # a server object in this process: no HTTP, no token
            self._in_process = True
            self.url = "in-process"
            self.name = name or url.name
            self._client = Client(url, timeout=timeout)
        else:
            self._in_process = False
            self.url = url
            self.name = name
            self._client = Client(url, auth=token, timeout=timeout, verify=shared_context())
        self.token = token
        self.timeout = timeout

    @classmethod
    def in_process(
        cls, server: FastMCP, timeout: float = DEFAULT_TIMEOUT, name: str | None = None
    ) -> DeviceClient:
        """A client for a server object in this process (no HTTP), with the same error handling."""
        return cls(server, None, timeout, name)

    async def __aenter__(self) -> DeviceClient:
        await self._guard(self._client.__aenter__())
        return self

    async def __aexit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self._client.__aexit__(exc_type, exc, tb)

    async def get_state(self) -> dict[str, Any]:
        """Call the device's read-only ``get_state`` tool and return the state as a dict."""
        result = await self._call("get_state", {})
        state = _as_object(result)
        if state is None:
            raise DeviceError(
                f"{self._who()}: get_state returned {type(result.data).__name__}, not a JSON object; "
                "the driver's get_state must return a dict"
            )
        return state

    async def call(self, tool: str, args: dict[str, Any] | None = None) -> Any:
        """Call ``tool`` with ``args``; return its data (structured result, or text)."""
        result = await self._call(tool, args or {})
        if result.data is not None:
            return result.data
        if result.structured_content is not None:
            return result.structured_content
        return "\n".join(block.text for block in result.content if isinstance(block, mcp.types.TextContent))

    async def list_tools(self) -> list[mcp.types.Tool]:
        """The device's tools, with their schemas and annotations."""

        async def run() -> list[mcp.types.Tool]:
            async with self._client:
                return await self._client.list_tools()

        return await self._guard(run())

    async def _call(self, tool: str, args: dict[str, Any]) -> Any:
        async def run() -> Any:
            async with self._client:
                return await self._client.call_tool(tool, args)

        return await self._guard(run(), tool=tool)

    async def _guard(self, work: Any, tool: str | None = None) -> Any:
        """Run ``work`` within the timeout and turn every failure into an actionable DeviceError."""
        try:
            # One deadline for connect + call: fastmcp's own connect timeout is 30 s, too long
            # for a health check or a CLI that should say "not answering" promptly.
            async with asyncio.timeout(self.timeout):
                return await work
        except ToolError as error:
            what = f"{tool} failed" if tool else "request failed"
            raise DeviceError(f"{self._who()}: {what}: {error}") from None
        except (TimeoutError, httpx.TimeoutException) as error:
            raise DeviceError(self._timeout_message()) from error
        except MCPError as error:
            raise DeviceError(await self._diagnose(error)) from None
        except Exception as error:
            if _is_timeout(error):
                raise DeviceError(self._timeout_message()) from error
            if _is_connect_error(error):
                raise DeviceError(self._nothing_listening()) from None
            raise DeviceError(f"{self._who()}: {type(error).__name__}: {error}") from None

    async def _diagnose(self, error: MCPError) -> str:
        """Explain an MCP-level failure. The SDK hides the HTTP status, so ask the server once more."""
        if self._in_process:
            return f"{self._who()}: {error}"
        try:
            async with httpx.AsyncClient(timeout=min(self.timeout, 3.0), verify=shared_context()) as http:
                headers = {"Authorization": f"Bearer {self.token}"} if self.token else {}
                response = await http.post(self.url, headers=headers, json={})
        except httpx.HTTPError:
            return f"{self._who()}: {error}"
        if response.status_code == 401:
            return (
                f"the device at {self.url} refused the token: use the token from the data directory of "
                "the machine that serves it (<data_dir>/token), or set token = ... for this instance "
                "in rosaos.toml"
            )
        if response.status_code == 404:
            return f"no MCP server at {self.url} (404): device URLs end in /mcp, e.g. http://host:9100/mcp"
        return f"{self._who()}: {error} (HTTP {response.status_code})"

    def _who(self) -> str:
        return f"{self.name} ({self.url})" if self.name else self.url

    def _nothing_listening(self) -> str:
        instance = self.name or "NAME"
        return (
            f"nothing is listening at {self.url}: is `rosaos up` or `rosaos serve-device {instance}` running?"
        )

    def _timeout_message(self) -> str:
        return (
            f"{self._who()} did not answer within {self.timeout:g} s: the device or its host may be busy, "
            "hung or unreachable; check that its host is up, or allow a longer timeout"
        )


def _as_object(result: Any) -> dict[str, Any] | None:
    """A tool result as a JSON object: structured data, or text that parses as one."""
    if isinstance(result.data, dict):
        return result.data
    if isinstance(result.structured_content, dict):
        content = result.structured_content
        # FastMCP wraps non-object return values as {"result": ...}.
        inner = content.get("result") if set(content) == {"result"} else content
        if isinstance(inner, dict):
            return inner
    for block in result.content:
        if isinstance(block, mcp.types.TextContent):
            try:
                parsed = json.loads(block.text)
            except ValueError:
                continue
            if isinstance(parsed, dict):
                return parsed
    return None


def _chain(error: BaseException) -> list[BaseException]:
    """The error and its causes/contexts, so wrapped transport errors are recognised."""
    seen: list[BaseException] = []
    current: BaseException | None = error
    while current is not None and current not in seen:
        seen.append(current)
        current = current.__cause__ or current.__context__
    return seen


def _is_connect_error(error: BaseException) -> bool:
    # fastmcp reports a refused connection as RuntimeError("Client failed to connect: ...")
    # caused by the transport's ConnectError (from httpx2, which we do not import).
    return any(
        isinstance(e, ConnectionError | httpx.ConnectError) or type(e).__name__ == "ConnectError"
        for e in _chain(error)
    )


def _is_timeout(error: BaseException) -> bool:
    return any(isinstance(e, TimeoutError) or "Timeout" in type(e).__name__ for e in _chain(error))
