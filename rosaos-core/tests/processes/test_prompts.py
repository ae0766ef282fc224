"""Process prompts: base prompt, one section per granted device, then the task."""

from __future__ import annotations

from rosaos.processes.jobs import GrantedDevice
from rosaos.processes.prompts import DEFAULT_PROCESS_PROMPT, base_process_prompt, process_system_prompt
from rosaos.processes.tool_list import DeviceTools, ToolSummary


def device(name: str, driver: str = "tapo") -> GrantedDevice:
    return GrantedDevice(
        name=name,
        driver=driver,
        url=f"http://127.0.0.1:9/{name}/mcp",
        token="t",
        description=f"The {name} description.",
        prompt=f"How to drive {name}.",
    )


def test_parts_come_in_order_base_devices_task() -> None:
    prompt = process_system_prompt("BASE", "turn the light red", [device("kitchen_light")])
    assert (
        prompt.index("BASE") < prompt.index("How to drive kitchen_light") < prompt.index("turn the light red")
    )


def test_every_task_on_the_same_devices_shares_the_prompt_up_to_the_task() -> None:
    """A local model server that caches the prompt prefix prefills only the task of the next one."""
    devices = [device("kitchen_light"), device("reachy", "reachy")]
    first = process_system_prompt("BASE", "turn the light red", devices)
    second = process_system_prompt("BASE", "dim the light", devices)
    shared = first.index("# Your task")
    assert first[:shared] == second[:shared]
    assert first[shared:] == "# Your task\nturn the light red\n"


def test_each_device_is_headed_by_its_name_driver_and_description() -> None:
    prompt = process_system_prompt("BASE", "task", [device("kitchen_light")])
    assert "## kitchen_light (tapo)\nThe kitchen_light description.\n\nHow to drive kitchen_light." in prompt


def test_one_device_has_unprefixed_tools() -> None:
    assert "Its tools are named" not in process_system_prompt("BASE", "task", [device("kitchen_light")])


def test_several_devices_say_how_their_tools_are_prefixed() -> None:
    prompt = process_system_prompt("BASE", "task", [device("kitchen_light"), device("reachy", "reachy")])
    assert "You hold: kitchen_light, reachy." in prompt
    assert "Its tools are named `kitchen_light_<tool>`." in prompt
    assert "Its tools are named `reachy_<tool>`." in prompt


def test_no_devices_says_there_are_no_tools() -> None:
    assert "you have no tools" in process_system_prompt("BASE", "tell a joke", [])


def test_configured_base_prompt_replaces_the_default() -> None:
    assert base_process_prompt("Be terse.") == "Be terse."
    assert base_process_prompt(None) == DEFAULT_PROCESS_PROMPT
    assert base_process_prompt("  ") == DEFAULT_PROCESS_PROMPT


def listed_tools() -> DeviceTools:
    return DeviceTools(
        tools=(
            ToolSummary.of(
                "set_brightness",
                "Set the brightness in percent.\n\nColour stays as it is.",
                {"properties": {"brightness": {"type": "integer"}}, "required": ["brightness"]},
            ),
            ToolSummary.of(
                "speak", "Say something.", {"properties": {"text": {}, "voice": {}}, "required": ["text"]}
            ),
            ToolSummary.of("get_state", "Read the light.", {"properties": {}}),
        )
    )


def test_the_tool_list_comes_from_the_server_metadata_with_its_parameters() -> None:
    prompt = process_system_prompt(
        "BASE", "task", [device("kitchen_light")], {"kitchen_light": listed_tools()}
    )
    assert "Tools:\n- `set_brightness(brightness)`: Set the brightness in percent.\n" in prompt
    assert "- `speak(text, voice?)`: Say something." in prompt  # optional parameters end in ?
    assert "- `get_state`: Read the light." in prompt
    assert "Colour stays as it is" not in prompt  # the first paragraph only: the schema has the rest


def test_the_tool_list_names_only_the_tools_the_process_is_offered() -> None:
    attached = device("reachy", "reachy").model_copy(update={"tools": ["speak"]})
    prompt = process_system_prompt("BASE", "task", [attached], {"reachy": listed_tools()})
    assert "`speak(text, voice?)`" in prompt
    assert "set_brightness" not in prompt and "get_state" not in prompt
