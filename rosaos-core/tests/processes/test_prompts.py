"""Process prompts: base prompt, one section per granted device, then the task."""

from __future__ import annotations

from rosaos.processes.jobs import GrantedDevice
from rosaos.processes.prompts import DEFAULT_PROCESS_PROMPT, base_process_prompt, process_system_prompt


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


def test_the_prompt_does_not_list_the_tools_their_schemas_already_give() -> None:
    # Issue 22: the model is sent every tool's name, parameters and description as its schema;
    # listing them in the prompt as well cost 1.5 KB of a light switch's prompt, on every request.
    prompt = process_system_prompt("BASE", "task", [device("kitchen_light"), device("reachy", "reachy")])
    assert "Tools:" not in prompt
    assert "How to drive kitchen_light." in prompt and "How to drive reachy." in prompt
