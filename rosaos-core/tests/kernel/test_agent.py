"""The kernel agent's prompt and conversation budget."""

from __future__ import annotations

from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    TextPart,
    ToolCallPart,
    ToolReturnPart,
    UserPromptPart,
)

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.kernel.agent import describe_devices, kernel_prompt, trim_history


def endpoint(name: str, **changes: object) -> DeviceEndpoint:
    fields: dict[str, object] = {
        "name": name,
        "driver": "tapo",
        "concurrency": "exclusive",
        "always_attached": False,
        "description": f"The {name.replace('_', ' ')}",
        "prompt": "Use the tools.",
        "url": "http://127.0.0.1:1/mcp",
        "token": "t",
        "status": "healthy",
    }
    fields.update(changes)
    return DeviceEndpoint(**fields)  # type: ignore[arg-type]


def test_the_prompt_lists_every_device_with_driver_concurrency_and_description() -> None:
    prompt = kernel_prompt(
        [endpoint("kitchen_light"), endpoint("reachy", driver="reachy", always_attached=True)]
    )
    assert "- kitchen_light (tapo, exclusive): The kitchen light" in prompt
    assert "- reachy (reachy, exclusive, always attached): The reachy" in prompt
    assert "launch_process" in prompt


def test_an_unavailable_device_is_marked_so_the_kernel_does_not_plan_on_it() -> None:
    listing = describe_devices([endpoint("turtlebot", url=None, status="failed")])
    assert listing == "- turtlebot (tapo, exclusive, unavailable: failed): The turtlebot"


def test_a_configured_prompt_replaces_the_default_and_gets_the_device_list() -> None:
    prompt = kernel_prompt([endpoint("lamp")], template="You run a lighthouse.\n{devices}\nBe brief.")
    assert prompt == "You run a lighthouse.\n- lamp (tapo, exclusive): The lamp\nBe brief."


def test_a_configured_prompt_without_the_placeholder_still_gets_the_devices() -> None:
    prompt = kernel_prompt([endpoint("lamp")], template="You run a lighthouse.")
    assert prompt.startswith("You run a lighthouse.\n\nDevices:\n- lamp")


def turn(n: int) -> list[ModelMessage]:
    """One user turn with a tool call and its return: four messages."""
    return [
        ModelRequest(parts=[UserPromptPart(f"[User typed] {n}")]),
        ModelResponse(parts=[ToolCallPart("list_devices", {}, tool_call_id=f"c{n}")]),
        ModelRequest(parts=[ToolReturnPart("list_devices", [], tool_call_id=f"c{n}")]),
        ModelResponse(parts=[TextPart(f"reply {n}")]),
    ]


def test_history_within_budget_is_kept_whole() -> None:
    history = turn(1) + turn(2)
    assert trim_history(history, 8) == history


def test_history_is_cut_at_a_user_turn_so_no_tool_return_is_orphaned() -> None:
    history = turn(1) + turn(2) + turn(3)
    trimmed = trim_history(history, 6)
    assert trimmed == history[8:]
    first = trimmed[0]
    assert isinstance(first, ModelRequest)
    assert isinstance(first.parts[0], UserPromptPart)


def test_history_is_bounded_by_size_as_well_as_by_count() -> None:
    long = [
        ModelRequest(parts=[UserPromptPart("[Process callback] process=1 status=ok\noutput: " + "x" * 5000)]),
        ModelResponse(parts=[TextPart("done")]),
    ]
    history = long + turn(2) + turn(3)
    trimmed = trim_history(history, 40, max_chars=2000)
    assert trimmed == history[2:]
    assert trim_history(history, 40, max_chars=100_000) == history
    assert trim_history(long, 40, max_chars=1000) == []  # one turn too big to carry: none carried


def test_a_cut_goes_down_to_half_the_budget_so_the_next_turns_keep_the_same_prefix() -> None:
    history = turn(1) + turn(2) + turn(3) + turn(4) + turn(5)  # 20 messages
    trimmed = trim_history(history, 16)
    assert trimmed == history[12:]  # 8 messages: half of 16, not the 16 that would just fit
    grown = trim_history([*trimmed, *turn(6)], 16)
    assert grown[: len(trimmed)] == trimmed  # the next turn appends; nothing before it moved


def test_the_default_prompt_tells_the_model_about_every_timer_tool_and_timer_event() -> None:
    from rosaos.timers.timer_tools import TIMER_TOOL_NAMES

    prompt = kernel_prompt([])
    assert all(name in prompt for name in TIMER_TOOL_NAMES)
    assert "[Timer fired]" in prompt and "late" in prompt


def test_the_default_prompt_tells_the_model_about_every_memory_tool_it_is_offered() -> None:
    from rosaos.memory.memory_tools import MEMORY_TOOL_NAMES
    from rosaos.models.tool_schemas import KERNEL_HIDDEN

    prompt = kernel_prompt([])
    assert all(name in prompt for name in MEMORY_TOOL_NAMES if name not in KERNEL_HIDDEN)
    assert not any(f"{name}," in prompt or f"{name})" in prompt for name in KERNEL_HIDDEN)


def test_the_default_prompt_says_stop_preempts_and_questions_read_state_without_a_lease() -> None:
    from rosaos.kernel.stop_tools import STOP_TOOL_NAMES

    prompt = kernel_prompt([])
    assert all(f"{name}(" in prompt for name in STOP_TOOL_NAMES)
    assert "never launch_process" in prompt and "no lease" in prompt and "never radians" in prompt
