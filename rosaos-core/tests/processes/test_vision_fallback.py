"""A text-only model that rejects image parts still completes "take a picture and tell me what you see".

The model is a ``FunctionModel`` that answers HTTP 400 to any request with a picture in it, as a
text-only provider does; the tools return a picture (as a camera tool does for a model that takes
images) and describe it by path (as the Reachy's ``describe_image`` does).
"""

from __future__ import annotations

import pytest
from pydantic_ai import Agent, ToolReturn
from pydantic_ai.exceptions import ModelHTTPError
from pydantic_ai.messages import (
    BinaryContent,
    ModelMessage,
    ModelRequest,
    ModelResponse,
    TextPart,
    ToolCallPart,
    ToolReturnPart,
)
from pydantic_ai.models.function import AgentInfo, FunctionModel

from rosaos.processes.vision import IMAGE_REMOVED, ImageFallbackModel, has_images

pytestmark = pytest.mark.asyncio

JPEG = BinaryContent(data=b"\xff\xd8\xff\xe0fake", media_type="image/jpeg")


async def test_a_rejected_picture_is_sent_again_without_it_and_the_describe_tool_answers() -> None:
    requests: list[list[ModelMessage]] = []

    def text_only(messages: list[ModelMessage], info: AgentInfo) -> ModelResponse:
        requests.append(messages)
        if has_images(messages):
            raise ModelHTTPError(400, "text-only", {"error": "image input is not supported"})
        returns = [
            p
            for m in messages
            if isinstance(m, ModelRequest)
            for p in m.parts
            if isinstance(p, ToolReturnPart)
        ]
        if not returns:
            return ModelResponse(parts=[ToolCallPart("take_picture", {})])
        if len(returns) == 1:
            return ModelResponse(parts=[ToolCallPart("describe_image", {"path": "pic-1.jpg"})])
        return ModelResponse(parts=[TextPart(f"I see: {returns[-1].content}")])

    agent = Agent(ImageFallbackModel(FunctionModel(text_only)))

    @agent.tool_plain
    def take_picture() -> ToolReturn:
        return ToolReturn(return_value={"path": "pic-1.jpg"}, content=[JPEG])

    @agent.tool_plain
    def describe_image(path: str) -> str:
        return f"a person at a desk in {path}"

    result = await agent.run("take a picture and tell me what you see")
    assert result.output == "I see: a person at a desk in pic-1.jpg"
    rejected, *after = [r for r in requests if any(isinstance(m, ModelRequest) for m in r)][1:]
    assert has_images(rejected)  # the picture was sent once, and refused ...
    assert after and not any(has_images(r) for r in after)  # ... then never again
    assert IMAGE_REMOVED in str(after[0][-1])  # and the model was told why it is gone
