"""A question about state is answered from ``device_state``, not by a process.

"how bright is the kitchen light?" and "what's the volume?" are read as questions (issue 20's
third round: brightness, colour and volume are answered from state); the offline engine reads the
state through the kernel's lease-free ``device_state``, so the answer comes while another process
holds the device. A question that names no device ("what's the volume?") reads every device and
answers from those whose state says.
"""

from __future__ import annotations

from typing import Any

import pytest
from pydantic_ai.messages import (
    ModelMessage,
    ModelRequest,
    ModelResponse,
    TextPart,
    ToolCallPart,
    ToolReturnPart,
    UserPromptPart,
)

from rosaos.config import RosaosConfig
from rosaos.devices.world import build_world
from rosaos.intents.grammar.state_words import called
from rosaos.intents.grammar.vocabulary import device_vocabularies
from rosaos.models.kernel_model import LocalIntentModel
from rosaos.plugins import load_drivers

TOOLS = ["launch_process", "stop", "device_state"]


@pytest.fixture(scope="module")
def model() -> LocalIntentModel:
    world = build_world(RosaosConfig(), load_drivers())
    return LocalIntentModel(device_vocabularies(world.instances.values()))


@pytest.mark.parametrize(
    ("said", "asked", "device", "state", "answer"),
    [
        ("how bright is the kitchen light?", {"device": "kitchen_light"}, "kitchen_light",
         {"on": True, "brightness": 70}, "The kitchen light is at 70% brightness."),
        # A device named after its product is called by that name: not "the spotify's volume".
        ("what's the volume?", {}, "spotify", {"is_playing": False, "volume": 40}, "Spotify's volume is at 40%."),
    ],
)  # fmt: skip
def test_a_state_question_reads_device_state(
    model: LocalIntentModel, said: str, asked: dict[str, str], device: str, state: dict[str, Any], answer: str
) -> None:
    messages: list[ModelMessage] = [ModelRequest(parts=[UserPromptPart(said)])]  # a bare prompt: typed text
    [call] = model.respond(messages, TOOLS)
    assert isinstance(call, ToolCallPart) and call.tool_name == "device_state"
    assert call.args_as_dict() == asked
    driver = build_world(RosaosConfig(), load_drivers()).get(device).spec.name
    result = {
        "device": device,
        "called": called(device, driver),  # as the kernel's device_state tool answers
        "state": state,
        "held_by": [{"id": 3, "task": "a long task"}],
        "said": [],
    }
    messages += [
        ModelResponse(parts=[call]),
        ModelRequest(parts=[ToolReturnPart("device_state", result, tool_call_id=call.tool_call_id)]),
    ]
    assert model.respond(messages, TOOLS) == [TextPart(answer)]
