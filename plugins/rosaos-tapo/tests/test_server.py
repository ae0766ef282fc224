"""The bulb's MCP tools, driven through FastMCP's in-memory client on a simulated L530E."""

from __future__ import annotations

from typing import Any

import pytest

from rosaos_tapo.colors import NAMED_COLORS

STATE_KEYS = {"on", "brightness", "hue", "saturation", "color_temp"}
TOOLS = {
    "get_state",
    "turn_on",
    "turn_off",
    "toggle",
    "set_brightness",
    "adjust_brightness",
    "set_color_temp",
    "adjust_color_temp",
    "set_color",
    "set_color_name",
}


# The tool list


async def test_server_offers_exactly_the_light_tools(open_bulb: Any) -> None:
    async with open_bulb() as bulb:
        tools = await bulb.client.list_tools()
    assert {tool.name for tool in tools} == TOOLS


async def test_every_tool_has_a_description_and_full_annotations(open_bulb: Any) -> None:
    async with open_bulb() as bulb:
        tools = await bulb.client.list_tools()
    for tool in tools:
        assert (tool.description or "").strip(), tool.name
        hints = tool.annotations
        assert hints is not None, tool.name
        assert hints.read_only_hint is not None, tool.name
        assert hints.destructive_hint is False, tool.name
        assert hints.idempotent_hint is not None, tool.name


async def test_only_get_state_is_read_only(open_bulb: Any) -> None:
    async with open_bulb() as bulb:
        tools = await bulb.client.list_tools()
    read_only = {tool.name for tool in tools if tool.annotations and tool.annotations.read_only_hint}
    assert read_only == {"get_state"}


async def test_relative_tools_are_not_idempotent(open_bulb: Any) -> None:
    async with open_bulb() as bulb:
        tools = await bulb.client.list_tools()
    repeated_changes = {
        tool.name for tool in tools if tool.annotations and not tool.annotations.idempotent_hint
    }
    assert repeated_changes == {"toggle", "adjust_brightness", "adjust_color_temp"}


# get_state and the simulator's initial state


async def test_get_state_returns_exactly_the_bench_keys(open_bulb: Any) -> None:
    async with open_bulb() as bulb:
        state = await bulb.call("get_state")
    assert set(state) == STATE_KEYS


async def test_sim_initial_state_is_honoured(open_bulb: Any) -> None:
    async with open_bulb(on=True, brightness=60, hue=0, saturation=0, color_temp=2700) as bulb:
        state = await bulb.call("get_state")
    assert state == {"on": True, "brightness": 60, "hue": 0, "saturation": 0, "color_temp": 2700}


async def test_sim_initial_colour_mode_reports_color_temp_zero(open_bulb: Any) -> None:
    async with open_bulb(on=True, hue=240, saturation=80, color_temp=0) as bulb:
        state = await bulb.call("get_state")
    assert (state["hue"], state["saturation"], state["color_temp"]) == (240, 80, 0)


# Switching


async def test_turn_on_lights_an_off_bulb_at_its_old_brightness(open_bulb: Any) -> None:
    async with open_bulb(on=False, brightness=70) as bulb:
        state = await bulb.call("turn_on")
    assert state["on"] is True
    assert state["brightness"] == 70


async def test_turn_off_switches_the_light_off(open_bulb: Any) -> None:
    async with open_bulb(on=True) as bulb:
        state = await bulb.call("turn_off")
    assert state["on"] is False


async def test_toggle_flips_on_and_off(open_bulb: Any) -> None:
    async with open_bulb(on=False) as bulb:
        first = await bulb.call("toggle")
        second = await bulb.call("toggle")
    assert (first["on"], second["on"]) == (True, False)


async def test_a_change_is_visible_to_a_later_get_state(open_bulb: Any) -> None:
    async with open_bulb(on=False) as bulb:
        await bulb.call("set_brightness", brightness=35)
        state = await bulb.call("get_state")
    assert (state["on"], state["brightness"]) == (True, 35)


# Brightness


async def test_set_brightness_turns_an_off_bulb_on(open_bulb: Any) -> None:
    # bench home-lamp-brightness: "Set the living room lamp to 20 percent"
    async with open_bulb(on=False, brightness=60, color_temp=2700) as bulb:
        state = await bulb.call("set_brightness", brightness=20)
    assert state == {"on": True, "brightness": 20, "hue": 0, "saturation": 0, "color_temp": 2700}


async def test_set_brightness_zero_turns_off_and_keeps_the_level(open_bulb: Any) -> None:
    async with open_bulb(on=True, brightness=60) as bulb:
        state = await bulb.call("set_brightness", brightness=0)
    assert (state["on"], state["brightness"]) == (False, 60)


@pytest.mark.parametrize("brightness", [-1, 101])
async def test_set_brightness_out_of_range_is_a_tool_error(open_bulb: Any, brightness: int) -> None:
    async with open_bulb(on=True, brightness=60) as bulb:
        message = await bulb.error("set_brightness", brightness=brightness)
        state = await bulb.call("get_state")
    assert "brightness" in message
    assert "100" in message or "0" in message
    assert state["brightness"] == 60


async def test_adjust_brightness_dims_relative_to_the_current_level(open_bulb: Any) -> None:
    # bench home-lamp-dim: "Dim the living room lamp" → brightness below 60
    async with open_bulb(on=True, brightness=60) as bulb:
        state = await bulb.call("adjust_brightness", change=-25)
    assert state["brightness"] == 35


async def test_adjust_brightness_never_goes_below_one(open_bulb: Any) -> None:
    async with open_bulb(on=True, brightness=10) as bulb:
        state = await bulb.call("adjust_brightness", change=-50)
    assert (state["on"], state["brightness"]) == (True, 1)


async def test_adjust_brightness_never_goes_above_100(open_bulb: Any) -> None:
    async with open_bulb(on=False, brightness=90) as bulb:
        state = await bulb.call("adjust_brightness", change=25)
    assert (state["on"], state["brightness"]) == (True, 100)


# Colour temperature


async def test_adjust_color_temp_warms_from_the_current_temperature(open_bulb: Any) -> None:
    async with open_bulb(on=True, brightness=100, hue=0, saturation=0, color_temp=4000) as bulb:
        state = await bulb.call("adjust_color_temp", change=-700)
    assert state == {"on": True, "brightness": 100, "hue": 0, "saturation": 0, "color_temp": 3300}


async def test_adjust_color_temp_stays_within_what_the_bulb_can_do(open_bulb: Any) -> None:
    async with open_bulb(on=False, color_temp=6000) as bulb:
        state = await bulb.call("adjust_color_temp", change=2000)
    assert (state["on"], state["color_temp"]) == (True, 6500)


async def test_adjust_color_temp_from_a_colour_starts_at_neutral_white(open_bulb: Any) -> None:
    async with open_bulb(on=True, hue=240, saturation=100, color_temp=0) as bulb:
        state = await bulb.call("adjust_color_temp", change=-700)
    assert state["color_temp"] == 3300


async def test_set_color_temp_sets_white_and_keeps_brightness_and_colour(open_bulb: Any) -> None:
    async with open_bulb(on=True, brightness=100, hue=0, saturation=0, color_temp=4000) as bulb:
        state = await bulb.call("set_color_temp", kelvin=2700)
    assert state == {"on": True, "brightness": 100, "hue": 0, "saturation": 0, "color_temp": 2700}


async def test_set_color_temp_turns_an_off_bulb_on(open_bulb: Any) -> None:
    async with open_bulb(on=False) as bulb:
        state = await bulb.call("set_color_temp", kelvin=6500)
    assert (state["on"], state["color_temp"]) == (True, 6500)


@pytest.mark.parametrize("kelvin", [2499, 6501])
async def test_set_color_temp_out_of_range_is_a_tool_error(open_bulb: Any, kelvin: int) -> None:
    async with open_bulb() as bulb:
        message = await bulb.error("set_color_temp", kelvin=kelvin)
    assert "kelvin" in message


# Colour


async def test_set_color_enters_colour_mode_and_turns_on(open_bulb: Any) -> None:
    async with open_bulb(on=False, brightness=80, color_temp=4000) as bulb:
        state = await bulb.call("set_color", hue=200, saturation=70)
    assert state == {"on": True, "brightness": 80, "hue": 200, "saturation": 70, "color_temp": 0}


async def test_set_color_with_brightness_sets_both(open_bulb: Any) -> None:
    async with open_bulb(on=True, brightness=80) as bulb:
        state = await bulb.call("set_color", hue=10, saturation=100, brightness=30)
    assert (state["hue"], state["brightness"]) == (10, 30)


@pytest.mark.parametrize(
    "args",
    [
        {"hue": 361, "saturation": 50},
        {"hue": 10, "saturation": 101},
        {"hue": 10, "saturation": 50, "brightness": 0},
    ],
)
async def test_set_color_out_of_range_is_a_tool_error(open_bulb: Any, args: dict[str, int]) -> None:
    async with open_bulb(on=True) as bulb:
        message = await bulb.error("set_color", **args)
    assert "Input should be" in message


# Colour names


async def test_set_color_name_green_matches_the_bench(open_bulb: Any) -> None:
    # bench home-bedroom-green: on, hue 100-140, saturation > 50, color_temp 0, brightness unchanged
    async with open_bulb(on=False, brightness=80, hue=0, saturation=0, color_temp=4000) as bulb:
        state = await bulb.call("set_color_name", name="green")
    assert state["on"] is True
    assert 100 <= state["hue"] <= 140
    assert state["saturation"] > 50
    assert state["color_temp"] == 0
    assert state["brightness"] == 80


async def test_set_color_name_warm_white_is_a_warm_colour_temperature(open_bulb: Any) -> None:
    # bench home-kitchen-warm: color_temp < 3300, nothing else moves
    async with open_bulb(on=True, brightness=100, hue=0, saturation=0, color_temp=4000) as bulb:
        state = await bulb.call("set_color_name", name="warm white")
    assert state == {"on": True, "brightness": 100, "hue": 0, "saturation": 0, "color_temp": 2700}


async def test_set_color_name_ignores_case_and_dashes(open_bulb: Any) -> None:
    async with open_bulb() as bulb:
        state = await bulb.call("set_color_name", name="  Sky-Blue ")
    assert (state["hue"], state["color_temp"]) == (200, 0)


async def test_set_color_name_unknown_suggests_the_closest_name(open_bulb: Any) -> None:
    async with open_bulb() as bulb:
        message = await bulb.error("set_color_name", name="grean")
    assert "did you mean 'green'" in message
    assert "set_color" in message


async def test_set_color_name_unknown_lists_the_known_names(open_bulb: Any) -> None:
    async with open_bulb() as bulb:
        message = await bulb.error("set_color_name", name="chartreuse-ish")
    assert all(name in message for name in NAMED_COLORS)


async def test_set_color_name_description_lists_every_colour(open_bulb: Any) -> None:
    async with open_bulb() as bulb:
        tools = {tool.name: tool for tool in await bulb.client.list_tools()}
    description = " ".join((tools["set_color_name"].description or "").split())
    missing = [name for name in NAMED_COLORS if name not in description]
    assert not missing, f"set_color_name's docstring does not mention {missing}"


@pytest.mark.parametrize("brightness", [True, "50", 50.5])
async def test_a_brightness_of_the_wrong_type_is_refused_not_coerced(open_bulb: Any, brightness: Any) -> None:
    async with open_bulb(on=True, brightness=40) as bulb:
        error = await bulb.error("set_brightness", brightness=brightness)
        assert "brightness" in error
        assert (await bulb.state())["brightness"] == 40
