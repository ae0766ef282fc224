"""Which tools of a granted device a process model is offered (issue 22: each one is sent on every request)."""

from __future__ import annotations

from rosaos.processes.jobs import GrantedDevice
from rosaos.processes.tool_offer import KERNEL_ONLY, asks_for_on_request_tools, offered_names

EXPERT = ["list_topics", "publish", "set_param"]
WORDS = r"\b(topics?|param(eter)?s?|publish\w*)\b|(^|\s)/[a-z_]"


def robot(**changes: object) -> GrantedDevice:
    fields: dict[str, object] = {
        "name": "turtlebot",
        "driver": "ros",
        "url": "http://127.0.0.1:9/mcp",
        "token": "t",
        "description": "A robot.",
        "prompt": "Drive it.",
        "on_request_tools": EXPERT,
        "on_request_pattern": WORDS,
    }
    fields.update(changes)
    return GrantedDevice(**fields)  # type: ignore[arg-type]


def test_a_drive_or_a_search_is_not_offered_the_expert_tools() -> None:
    for task in ("Drive forward one meter.", "Undock, then search for a person and report it."):
        assert offered_names(robot(), task) == (None, frozenset(EXPERT) | KERNEL_ONLY)


def test_a_task_that_speaks_of_them_gets_them() -> None:
    for task in (
        "List the topics.",
        "Publish 0.2 on /cmd_vel.",
        "set linear.x to 0.2 on /cmd_vel",
        "call set_param",
    ):
        assert asks_for_on_request_tools(robot(), task), task
        assert offered_names(robot(), task) == (None, KERNEL_ONLY)


def test_a_device_without_expert_tools_is_offered_everything_or_its_own_list() -> None:
    plain = robot(on_request_tools=[], on_request_pattern=None)
    assert offered_names(plain, "Drive forward.") == (None, KERNEL_ONLY)
    attached = robot(name="reachy", tools=["speak"], on_request_tools=[], on_request_pattern=None)
    assert offered_names(attached, "Turn on the light.") == (frozenset({"speak"}), KERNEL_ONLY)
