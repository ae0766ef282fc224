"""A device host's log stays readable and bounded: refusals in one line, routine traffic quiet."""

from __future__ import annotations

import io
import logging
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastmcp import Client, FastMCP

from rosaos.devices.host_logging import FASTMCP_LOGGER, ROUTINE_LOGGERS, ExpectedToolErrors, open_rotated_log
from rosaos.drivers import DeviceError


@pytest.fixture
def captured() -> Iterator[io.StringIO]:
    """Everything logged while the test runs, through the host's filter, as the host's file gets it."""
    text = io.StringIO()
    handler = logging.StreamHandler(text)
    handler.setFormatter(logging.Formatter("%(levelname)s %(name)s %(message)s"))
    handler.addFilter(ExpectedToolErrors())
    fastmcp = logging.getLogger(FASTMCP_LOGGER)  # logs through its own handlers, not the root's
    fastmcp.addHandler(handler)
    try:
        yield text
    finally:
        fastmcp.removeHandler(handler)


def _server() -> FastMCP:
    server = FastMCP("bulb")

    @server.tool
    def set_level(level: int) -> str:
        """Set the level."""
        if level > 100:
            raise DeviceError("refused: level 101 is above 100; use 0-100")
        if level < 0:
            raise RuntimeError("the driver has a bug")
        return "ok"

    return server


async def test_a_refused_tool_call_is_one_line_without_a_traceback(captured: io.StringIO) -> None:
    async with Client(_server()) as client:
        result = await client.call_tool("set_level", {"level": 101}, raise_on_error=False)
    assert result.is_error
    log = captured.getvalue()
    assert "refused: level 101 is above 100" in log
    assert "Traceback" not in log
    assert len([line for line in log.splitlines() if "set_level" in line]) == 1


async def test_a_driver_bug_keeps_its_traceback(captured: io.StringIO) -> None:
    async with Client(_server()) as client:
        await client.call_tool("set_level", {"level": -1}, raise_on_error=False)
    assert "Traceback" in captured.getvalue()
    assert "the driver has a bug" in captured.getvalue()


def test_a_big_log_is_rotated_when_the_host_starts(tmp_path: Path) -> None:
    path = tmp_path / "logs" / "reachy.log"
    path.parent.mkdir()
    path.write_bytes(b"x" * 2000)
    with open_rotated_log(path, max_bytes=1000) as handle:
        handle.write(b"new start\n")
    assert path.read_bytes() == b"new start\n"
    assert (tmp_path / "logs" / "reachy.log.1").stat().st_size == 2000
    with open_rotated_log(path, max_bytes=1000) as handle:  # small: appended to, not rotated
        handle.write(b"again\n")
    assert path.read_bytes() == b"new start\nagain\n"


def test_http_clients_do_not_log_every_request() -> None:
    from rosaos.devices.host_logging import configure_host_logging

    configure_host_logging()
    assert all(logging.getLogger(name).getEffectiveLevel() >= logging.WARNING for name in ROUTINE_LOGGERS)
    assert all(
        any(isinstance(f, ExpectedToolErrors) for f in handler.filters)
        for handler in logging.getLogger(FASTMCP_LOGGER).handlers
    )
