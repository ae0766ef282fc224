"""How a ``[Device notice]`` reads to the kernel model, and how the offline engine reads it back.

::

    [Device notice] device=turtlebot name=battery_low importance=notify data={"battery": 0.12}
    "turtlebot: battery at 12 %"

The first line carries the fields, the second the driver's sentence for people, as a JSON string:
a device's text is data, and no line of it may pass for an event header
(:mod:`rosaos.kernel.event_text`). A notice posted by hand (no ``name``) keeps the older one-line
shape: ``device=X importance=info "<message>"``.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from typing import Any

from rosaos.kernel.events import DeviceNotice

_HEAD = re.compile(
    r"^device=(?P<device>\S+)(?: name=(?P<name>\S+))?(?: importance=(?P<importance>info|notify))?"
    r"(?: data=(?P<data>\{.*\}))?(?:\n|\s|$)"
)


def render_notice(notice: DeviceNotice) -> str:
    """The event text for ``notice``."""
    head = f"[Device notice] device={notice.device}"
    if notice.name:
        head += f" name={notice.name}"
    head += f" importance={notice.importance}"
    if notice.name:
        if notice.data:
            head += f" data={json.dumps(notice.data, ensure_ascii=False, sort_keys=True)}"
        return f"{head}\n{json.dumps(notice.message, ensure_ascii=False)}"
    return f"{head} {json.dumps(notice.message, ensure_ascii=False)}"


def _unquoted(text: str) -> str:
    if text.startswith('"'):
        try:
            value = json.loads(text)
        except ValueError:
            return text
        if isinstance(value, str):
            return value
    return text


@dataclass(frozen=True)
class ReadNotice:
    """A ``[Device notice]`` body, read back (see :func:`read_notice`)."""

    device: str
    message: str
    name: str | None = None
    importance: str = "info"
    data: dict[str, Any] = field(default_factory=dict)


def read_notice(body: str) -> ReadNotice:
    """The fields of a rendered notice body (the text after ``[Device notice]``)."""
    match = _HEAD.match(body.strip())
    if match is None:
        return ReadNotice(device="", message=body.strip())
    data: dict[str, Any] = {}
    if match.group("data"):
        try:
            loaded = json.loads(match.group("data"))
        except ValueError:
            loaded = {}
        data = loaded if isinstance(loaded, dict) else {}
    return ReadNotice(
        device=match.group("device"),
        message=_unquoted(body.strip()[match.end() :].strip() or body.strip()),
        name=match.group("name"),
        importance=match.group("importance") or "info",
        data=data,
    )
