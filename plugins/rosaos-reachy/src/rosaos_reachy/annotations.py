"""The MCP tool annotations of the reachy tools, per the MCP spec's hints.

Nothing a desk robot does is destructive (every pose can be undone) except forgetting a face,
which deletes what was stored. Setting a pose twice is the same as once; an emotion, a speech
or a picture is a new event each time.
"""

from __future__ import annotations

from rosaos.drivers import CHANGES, DELETES, READ_ONLY, SETS

CLOUD_READ = READ_ONLY.model_copy(update={"idempotent_hint": False, "open_world_hint": True})
"""Asks a cloud model about a picture: reads only, but the answer differs each time."""
SET = SETS
ACT = CHANGES
DELETE = DELETES

__all__ = ["ACT", "CLOUD_READ", "DELETE", "READ_ONLY", "SET"]
