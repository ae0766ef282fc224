"""Which device call failure ends a process in error: the last one nothing made good."""

from __future__ import annotations

from rosaos.processes.tool_calls import ToolCall, ToolCallLog


def _call(device: str, tool: str, ok: bool) -> ToolCall:
    return ToolCall(device, tool, ok, None if ok else f"{tool} refused", 0.01)


def test_no_calls_and_only_successes_leave_nothing_unresolved() -> None:
    assert ToolCallLog().unresolved_failure() is None
    assert ToolCallLog([_call("lamp", "set_level", True)]).unresolved_failure() is None


def test_a_failure_at_the_end_is_unresolved() -> None:
    failed = _call("turtlebot", "drive", False)
    assert ToolCallLog([_call("turtlebot", "undock", True), failed]).unresolved_failure() == failed


def test_a_later_success_of_the_same_tool_on_the_same_device_makes_it_good() -> None:
    log = ToolCallLog(
        [
            _call("turtlebot", "drive", False),
            _call("turtlebot", "undock", True),
            _call("turtlebot", "drive", True),
        ]
    )
    assert log.unresolved_failure() is None


def test_a_success_elsewhere_does_not_make_a_failure_good() -> None:
    failed = _call("turtlebot", "drive", False)
    log = ToolCallLog([failed, _call("turtlebot", "get_state", True), _call("lamp", "drive", True)])
    assert log.unresolved_failure() == failed
