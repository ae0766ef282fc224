"""How a ``[Device notice]`` reads to an LLM kernel (the offline engine reads the typed notice).

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

from rosaos.events.types import DeviceNotice


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
