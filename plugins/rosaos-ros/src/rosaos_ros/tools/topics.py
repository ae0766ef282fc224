"""Topic tools: list, inspect, read and publish."""

from __future__ import annotations

import asyncio
from typing import Annotated, Any

from fastmcp import FastMCP
from pydantic import Field

from rosaos.drivers import DeviceError
from rosaos_ros.backend import RosBackend
from rosaos_ros.tools import MOVES, READ_ONLY, Fields, TopicName, TypeName

Seconds = Annotated[float, Field(gt=0, le=60, description="Seconds to wait for messages (at most 60).")]


def register(mcp: FastMCP, backend: RosBackend) -> None:
    """Add the topic tools."""

    @mcp.tool(annotations=READ_ONLY)
    async def list_topics() -> dict[str, Any]:
        """List every topic on the robot with its message type."""
        return {"topics": await backend.rosapi.topics()}

    @mcp.tool(annotations=READ_ONLY)
    async def topic_info(topic: TopicName) -> dict[str, Any]:
        """Show a topic's message type and the nodes (and counts) that publish and subscribe to it."""
        msg_type = await backend.rosapi.require_topic_type(topic)
        publishers, subscribers = await asyncio.gather(
            backend.rosapi.publishers(topic), backend.rosapi.subscribers(topic)
        )
        return {
            "topic": topic,
            "type": msg_type,
            "publisher_count": len(publishers),
            "subscriber_count": len(subscribers),
            "publishers": publishers,
            "subscribers": subscribers,
        }

    @mcp.tool(annotations=READ_ONLY)
    async def subscribe_once(topic: TopicName, timeout: Seconds = 5.0) -> dict[str, Any]:
        """Read the next message on a topic (waiting up to ``timeout`` s).

        Long arrays and binary data are summarised. For camera images use capture_image.
        """
        result = await backend.subscribe(topic, 1, timeout)
        if not result["messages"]:
            raise DeviceError(
                f"no message on {topic} within {timeout:g} s; topic_info shows whether anything publishes it"
            )
        return {"topic": topic, "type": result["type"], "message": result["messages"][0]}

    @mcp.tool(annotations=READ_ONLY)
    async def subscribe_for(
        topic: TopicName,
        duration: Seconds = 2.0,
        max_messages: Annotated[int, Field(ge=1, le=100, description="Stop after this many messages.")] = 20,
    ) -> dict[str, Any]:
        """Collect messages from a topic for ``duration`` s, or until ``max_messages`` arrived."""
        return await backend.subscribe(topic, max_messages, duration)

    @mcp.tool(annotations=MOVES)
    async def publish(topic: TopicName, msg: Fields, msg_type: TypeName = None) -> dict[str, Any]:
        """Publish one message on an allowed topic.

        Look the type up with message_details(topic) first and fill in its ``example``; never
        guess field names.
        Only topics on the instance's publish allow-list can be published (a refusal says how to
        allow one). The velocity topic is refused by default: use drive, move_distance or rotate.
        """
        return await backend.publish(topic, msg, msg_type, 0.0, 10.0)

    @mcp.tool(annotations=MOVES)
    async def publish_for(
        topic: TopicName,
        msg: Fields,
        duration: Annotated[
            float, Field(gt=0, le=30, description="Seconds to keep publishing (at most 30).")
        ],
        rate: Annotated[float, Field(ge=0.5, le=50, description="Messages per second.")] = 10.0,
        msg_type: TypeName = None,
    ) -> dict[str, Any]:
        """Publish the same message repeatedly, ``rate`` times a second for ``duration`` s, on an allowed topic."""
        return await backend.publish(topic, msg, msg_type, duration, rate)
