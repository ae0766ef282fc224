"""What a device host writes to its log (``<data_dir>/logs/devices/NAME.log``), and how big it gets.

A log is for the moments a person reads it: a start, a restart, a driver's warning, a real
failure. Routine traffic is not: HTTP client libraries log each request at INFO (a driver polling
its robot's daemon, every health check), and FastMCP logs every refused tool call with a full
traceback, though a refusal ("docked; call undock first") is the tool working as designed and
reaches the model as a message. Those stay one line or none. The file is rotated when a host
starts, so a device that runs for months does not fill the disk.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import BinaryIO

from pydantic import ValidationError

from rosaos.drivers import DeviceError

ROUTINE_LOGGERS = ("httpx", "httpcore", "mcp.server.lowlevel.server", "mcp.client", "uvicorn.access")
"""Libraries that log each request at INFO; only their warnings are kept."""
FASTMCP_LOGGER = "fastmcp"
MAX_LOG_BYTES = 5 * 1024 * 1024
"""A host log larger than this at a (re)start is moved to ``NAME.log.1`` (one generation kept)."""


class ExpectedToolErrors(logging.Filter):
    """Keeps a refused or invalid tool call to one line: the message, without the traceback."""

    def filter(self, record: logging.LogRecord) -> bool:
        error = record.exc_info[1] if record.exc_info else None
        expected = _expected(error)
        if expected is not None:
            record.msg = f"{record.getMessage()}: {type(expected).__name__}: {expected}"
            record.args = None
            record.exc_info = None
            record.exc_text = None
            record.levelno, record.levelname = logging.WARNING, "WARNING"
        return True


def _expected(error: BaseException | None) -> BaseException | None:
    """The device refusal behind ``error`` (FastMCP wraps the driver's exception), if it is one."""
    while error is not None:
        if isinstance(error, DeviceError | ValidationError):
            return error
        error = error.__cause__ or error.__context__
    return None


def configure_host_logging() -> None:
    """Log to stderr (the host's log file) at INFO, quiet the routine, shorten expected refusals."""
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    for name in ROUTINE_LOGGERS:
        logging.getLogger(name).setLevel(logging.WARNING)
    refusals = ExpectedToolErrors()
    # FastMCP logs through its own handlers and does not propagate to the root logger.
    for logger in (logging.getLogger(), logging.getLogger(FASTMCP_LOGGER)):
        for handler in logger.handlers:
            handler.addFilter(refusals)


def open_rotated_log(path: Path, max_bytes: int = MAX_LOG_BYTES) -> BinaryIO:
    """Open ``path`` for appending; first move it to ``path.1`` if it grew past ``max_bytes``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        if path.stat().st_size > max_bytes:
            path.replace(path.with_name(path.name + ".1"))
    except FileNotFoundError:
        pass
    return path.open("ab")
