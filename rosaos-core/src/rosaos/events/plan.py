"""The plan a process carries: exact tool calls, for the offline process engine and for people.

A process the local-intent engine launches has a readable task ("Turn on the kitchen light.")
and a typed :class:`Plan` beside it: ``launch_process(task, devices, plan=...)`` puts it on the
:class:`~rosaos.processes.jobs.WorkerJob`, the worker runs its steps without a model, and the
:class:`~rosaos.processes.jobs.WorkerCallback` brings it back to the kernel, where the offline
engine reads its reply, failure sentence and follow-up as fields. The plan is never written into
text to be parsed again; :func:`plan_text` renders it only for an LLM that runs the process.
"""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

PLAN_INTRO = "Planned device calls (rosaOS offline engine; you may follow them too):"
RESULT_PLACEHOLDER = "{result}"
_STATE_FIELD = re.compile(r"\{(\w+)(?::([^{}]*))?\}")
ERROR_PLACEHOLDER = "{error}"


class PlanStep(BaseModel):
    """One tool call on one device."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    device: str = Field(min_length=1)
    """Instance name; the process agent's tool is ``<device>_<tool>`` or bare ``<tool>``."""
    tool: str = Field(min_length=1)
    args: dict[str, Any] = Field(default_factory=dict)


class PlanAnswer(BaseModel):
    """A yes/no question answered from the state the last step returned."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    when: dict[str, Any] = Field(min_length=1)
    """State keys and the values that make the answer "yes"."""
    yes: str
    no: str


class Plan(BaseModel):
    """What a process does, step by step, and what it says when it is done."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    version: Literal[1] = 1
    steps: list[PlanStep] = Field(min_length=1)
    reply: str
    """Final output when every step succeeded; ``{result}`` becomes the last step's result."""
    failure: str = "Sorry, that failed: {error}"
    """Final output when a step failed; ``{error}`` becomes the tool's message."""
    ack: str = ""
    """What the kernel says once the process is launched."""
    answer: PlanAnswer | None = None
    fills_state: bool = False
    """Whether ``{key}`` placeholders in the reply (or answer) name keys of the last step's
    result, to fill in ("Playing {track} by {artist}."): a driver's question template."""
    quiet: bool = False
    """The kernel says nothing when this process succeeds (it only told the user something)."""
    then: FollowUp | None = None
    """What the kernel launches when this process succeeds ("…, and when you find someone, turn
    the lamp green"): the next step rides on the callback, so it survives in the event store."""

    @property
    def devices(self) -> list[str]:
        """The devices the steps touch, in order of first use."""
        return list(dict.fromkeys(step.device for step in self.steps))


class FollowUpLaunch(BaseModel):
    """One process of a follow-up: launched with task ``summary`` and ``plan`` on ``devices``."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    devices: list[str] = Field(min_length=1)
    summary: str = Field(min_length=1)
    plan: Plan


class FollowUp(BaseModel):
    """The next step of a plan, launched by the kernel on the callback (see :mod:`rosaos.intents.planning.follow_ups`)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    launches: list[FollowUpLaunch] = Field(min_length=1)
    summary: str
    """What the follow-up does, for replies ("turn the lamp green")."""
    when: dict[str, Any] | None = None
    """Result keys a step of this process must return for the follow-up to run (``{"found": true}``);
    None: the process succeeding is enough ("…, then …")."""
    unmet: str = ""
    """The process's output when ``when`` does not hold: the kernel sees it and launches nothing."""


Plan.model_rebuild()


def launch_args(summary: str, devices: Sequence[str], plan: Plan) -> dict[str, Any]:
    """The offline engine's ``launch_process`` arguments: the task in words, the devices, the plan.

    The plan travels as JSON data in the tool call (the kernel's history may go to an LLM later),
    and the tool validates it back into a :class:`Plan`: a typed argument, not text in the task."""
    return {
        "task": summary.strip(),
        "devices": list(devices),
        "plan": plan.model_dump(mode="json", exclude_none=True),
    }


def plan_text(plan: Plan) -> str:
    """The plan as an LLM running the process reads it: an intro line and the plan's JSON.

    Written for a model to read, never parsed back: the worker has the plan itself."""
    body = json.dumps(plan.model_dump(mode="json", exclude_none=True), ensure_ascii=False)
    return f"{PLAN_INTRO}\n{body}"


def result_data(content: Any) -> Any:
    """A tool result as data: MCP tools return structured content (a dict) or its JSON text,
    depending on the server; text that is not JSON stays text."""
    if isinstance(content, str):
        try:
            return json.loads(content)
        except json.JSONDecodeError:
            return content
    return content


def render_result(result: Any) -> str:
    """A tool result on one short line, for ``{result}`` in a reply ("on: false, brightness: 100")."""
    if isinstance(result, dict):
        return ", ".join(f"{key}: {_scalar(value)}" for key, value in result.items())
    return _scalar(result)


def fill_state(text: str, state: Any) -> str | None:
    """``text`` with each ``{key}`` or ``{key:spec}`` replaced by that key of ``state``, formatted;
    ``{result}`` is the whole state on one line. None when a key is missing or will not format."""
    try:
        return _STATE_FIELD.sub(lambda match: _state_field(match, state), text)
    except (KeyError, TypeError, ValueError):
        return None


def _state_field(match: re.Match[str], state: Any) -> str:
    key, spec = match.group(1), match.group(2) or ""
    if key == "result" and not spec:
        return render_result(state)
    if not isinstance(state, dict):
        raise TypeError("the result is not a mapping")
    value = state[key]
    if value is None:
        raise ValueError(f"{key} is null")
    return format(value, spec) if spec else _scalar(value)


def _scalar(value: Any) -> str:
    if isinstance(value, str):
        return value
    return json.dumps(value, ensure_ascii=False)
