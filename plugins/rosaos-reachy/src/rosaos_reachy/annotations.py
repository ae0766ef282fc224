"""The MCP tool annotations of the reachy tools, per the MCP spec's hints.

Nothing a desk robot does is destructive (every pose can be undone) except forgetting a face,
which deletes what was stored. Setting a pose twice is the same as once; an emotion, a speech
or a picture is a new event each time.
"""

from __future__ import annotations

from typing import Any

READ_ONLY: dict[str, Any] = {"readOnlyHint": True, "destructiveHint": False, "idempotentHint": True}
CLOUD_READ: dict[str, Any] = {
    "readOnlyHint": True,
    "destructiveHint": False,
    "idempotentHint": False,
    "openWorldHint": True,
}
SET: dict[str, Any] = {"readOnlyHint": False, "destructiveHint": False, "idempotentHint": True}
ACT: dict[str, Any] = {"readOnlyHint": False, "destructiveHint": False, "idempotentHint": False}
DELETE: dict[str, Any] = {"readOnlyHint": False, "destructiveHint": True, "idempotentHint": True}
