"""Receipts: what one tool call of a process really did, and the safety decision that applied.

A worker records a :class:`Receipt` for every tool call its process agent makes; they ride the
worker callback to the kernel, which keeps them in the activity log (``rosaos log``,
``GET /activity``) and shows them to the kernel model.

Drivers report a safety decision in a way the receipt can read:

- a refusal is an error whose text starts with ``refused:`` (as :class:`~rosaos.drivers.DeviceError`
  messages of safety rules do), e.g. ``refused: 0.8 m/s is above the velocity limit ...``;
- anything else (a clamped value, a deadman stop, a limit that shortened a move) is a ``safety``
  key in the tool's structured result holding a :class:`SafetyDecision`
  (:func:`safety_report` builds it).

A driver marks secret arguments in the tool's MCP meta, ``meta={"rosaos": {"secret_args":
["password"]}}`` (:func:`secret_args_meta`); those, and arguments named like secrets, are
redacted before a receipt leaves the worker.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterable, Mapping
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

SAFETY_KEY = "safety"
REFUSED_PREFIX = "refused:"
REDACTED = "[redacted]"
RESULT_LIMIT = 2000
"""Characters of a tool result kept in a receipt (JSON); longer results are cut and say so."""
SECRET_NAMES = re.compile(r"(pass(word)?|secret|token|api_?key|auth|credential|cookie)", re.IGNORECASE)
"""Argument names redacted even if no driver marked them."""

_CALL_ERROR = re.compile(r"^Error calling tool '[^']*':\s*")
"""How FastMCP heads a tool's error; the driver's own text follows."""

SafetyKind = Literal[
    "clamped",
    "refused",
    "deadman_stop",
    "limited",
    "stopped",
    "confirm_asked",
    "confirmed",
    "declined",
    "expired",
]


class SafetyDecision(BaseModel):
    """A safety rule that changed or stopped a tool call."""

    model_config = ConfigDict(extra="forbid")

    decision: SafetyKind
    """``refused``: not done (allow-list, limit, docked rule); ``clamped``: done with a changed value;
    ``deadman_stop``: the command stream went quiet and the device stopped; ``limited``: cut short
    by a bound (time, distance); ``stopped``: ended by a stop or the emergency stop;
    ``confirm_asked``, ``confirmed``, ``declined``, ``expired``: a person was asked before the call,
    and said yes, said no, or did not answer in time (:mod:`rosaos.confirmations.confirmation_desk`)."""
    rule: str = Field(default="", max_length=200)
    detail: str = Field(default="", max_length=1000)


class Receipt(BaseModel):
    """One tool call of a process: what was asked, what came back, when, and what safety did."""

    model_config = ConfigDict(extra="forbid")

    device: str
    tool: str
    arguments: dict[str, Any] = Field(default_factory=dict)
    ok: bool
    result: str | None = None
    """The result as JSON text, cut at :data:`RESULT_LIMIT` characters; ``None`` on error."""
    error: str | None = None
    started: float
    """Wall-clock start, seconds since the epoch."""
    duration: float = Field(ge=0)
    safety: SafetyDecision | None = None

    def line(self) -> str:
        """One line for the kernel model: ``turtlebot.drive(linear=0.2) -> ok [clamped: ...]``."""
        args = ", ".join(f"{key}={json.dumps(value)}" for key, value in self.arguments.items())
        # The device's words are data: quoted, so a line break in them cannot start a line.
        outcome = "ok" if self.ok else f"error: {json.dumps((self.error or '')[:200], ensure_ascii=False)}"
        text = f"{self.device}.{self.tool}({args}) -> {outcome}"
        if self.safety is not None and self.safety.decision != "refused":
            detail = json.dumps(self.safety.detail[:200], ensure_ascii=False)
            text += f" [{self.safety.decision}: {detail}]"
        return text


def safety_report(decision: SafetyKind, rule: str = "", detail: str = "") -> dict[str, Any]:
    """The ``safety`` entry a driver adds to a tool result, e.g. ``{**result, **safety_report(...)}``."""
    return {SAFETY_KEY: SafetyDecision(decision=decision, rule=rule, detail=detail).model_dump()}


def secret_args_meta(*names: str) -> dict[str, Any]:
    """The MCP tool meta that marks ``names`` as secret arguments: ``@mcp.tool(meta=...)``."""
    return {"rosaos": {"secret_args": list(names)}}


def secret_args_of(meta: Mapping[str, Any] | None) -> set[str]:
    """The secret argument names a tool's meta declares."""
    rosaos = (meta or {}).get("rosaos") or {}
    return set(rosaos.get("secret_args") or []) if isinstance(rosaos, Mapping) else set()


def redact(arguments: Mapping[str, Any], secret: Iterable[str] = ()) -> dict[str, Any]:
    """``arguments`` with secret values replaced by :data:`REDACTED` (marked names, and names like
    ``password`` or ``token`` at any depth)."""
    marked = set(secret)

    def clean(value: Any, name: str = "") -> Any:
        if name in marked or (name and SECRET_NAMES.search(name)):
            return REDACTED
        if isinstance(value, Mapping):
            return {key: clean(item, str(key)) for key, item in value.items()}
        if isinstance(value, list):
            return [clean(item) for item in value]
        return value

    return {key: clean(value, key) for key, value in arguments.items()}


def result_text(result: Any) -> str:
    """A tool result as JSON text for a receipt, cut at :data:`RESULT_LIMIT` characters."""
    try:
        text = json.dumps(result, default=_describe)
    except (TypeError, ValueError):
        text = json.dumps(str(result))
    if len(text) > RESULT_LIMIT:
        return f"{text[:RESULT_LIMIT]}... ({len(text)} characters in all)"
    return text


def safety_of(result: Any, error: str | None) -> SafetyDecision | None:
    """The safety decision a tool call reported: a ``refused:`` error, or a ``safety`` result key."""
    if error is not None:
        text = _CALL_ERROR.sub("", error.strip())
        if text.lower().startswith(REFUSED_PREFIX):
            detail = text[len(REFUSED_PREFIX) :].strip()
            return SafetyDecision(decision="refused", rule=_rule(detail), detail=detail[:1000])
        return None
    candidates = result if isinstance(result, list) else [result]
    for candidate in candidates:
        if isinstance(candidate, Mapping) and isinstance(candidate.get(SAFETY_KEY), Mapping):
            try:
                return SafetyDecision.model_validate(candidate[SAFETY_KEY])
            except ValueError:
                return None
    return None


def error_text(error: str) -> str:
    """A tool error as the driver wrote it (without FastMCP's "Error calling tool" head)."""
    return _CALL_ERROR.sub("", error.strip())


def _rule(detail: str) -> str:
    """The rule a refusal names, when it says: the allow-list, a limit, or the first clause."""
    lowered = detail.lower()
    for rule in ("allow-list", "velocity limit", "turn-rate limit", "never allowed", "docked", "denied"):
        if rule in lowered:
            return rule
    return detail.split(";")[0][:80]


def _describe(value: Any) -> Any:
    """JSON fallback for non-JSON values (pictures become a short note, not bytes)."""
    media_type = getattr(value, "media_type", None)
    if media_type is not None:
        return f"<{media_type}, {len(getattr(value, 'data', b''))} bytes>"
    return str(value)


RECEIPTS_HEADING = "tool calls:"
"""Heads the receipts in a rendered ``[Process callback]``, after the output or error line."""
RECEIPTS_SHOWN = 20
"""Receipts shown to the kernel model per callback (the first and the last ones)."""


def receipts_text(receipts: list[Receipt]) -> str:
    """The receipts as lines for the kernel model, or "" when there are none."""
    if not receipts:
        return ""
    shown = receipts
    if len(receipts) > RECEIPTS_SHOWN:
        half = RECEIPTS_SHOWN // 2
        shown = [*receipts[:half], *receipts[-half:]]
    lines = [f"- {receipt.line()}" for receipt in shown]
    if len(receipts) > RECEIPTS_SHOWN:
        lines.insert(RECEIPTS_SHOWN // 2, f"- ... ({len(receipts) - RECEIPTS_SHOWN} more calls)")
    return f"{RECEIPTS_HEADING}\n" + "\n".join(lines)
