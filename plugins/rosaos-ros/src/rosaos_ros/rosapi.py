"""Introspection and parameters through rosbridge's ``/rosapi/*`` services (``rosapi_msgs`` shapes).

Parameters are named as rosapi names them for ROS 2: ``/node:param`` (e.g.
``/motion_control:max_speed``); values travel as JSON strings.
"""

from __future__ import annotations

import asyncio
import json
from typing import Any

from rosaos.drivers import DeviceError
from rosaos_ros.bridge import RosbridgeClient, ServiceCallFailed


class Rosapi:
    """Read the robot's ROS graph and parameters."""

    def __init__(self, bridge: RosbridgeClient) -> None:
        self.bridge = bridge

    async def _call(self, rosapi_service: str, /, **args: Any) -> dict[str, Any]:
        return await self.bridge.call_service(f"/rosapi/{rosapi_service}", args)

    # Topics

    async def topics(self) -> list[dict[str, str]]:
        """Every topic with its type."""
        answer = await self._call("topics")
        names, types = answer.get("topics", []), answer.get("types", [])
        if len(types) != len(names):  # an old rosapi without types
            types = await asyncio.gather(*(self.topic_type(name) for name in names))
        return [{"name": name, "type": kind} for name, kind in zip(names, types, strict=True)]

    async def topic_type(self, topic: str) -> str:
        """The topic's message type, or "" when no node has it."""
        return str((await self._call("topic_type", topic=topic)).get("type") or "")

    async def require_topic_type(self, topic: str) -> str:
        """The topic's type; :class:`DeviceError` naming the fix when the topic does not exist."""
        msg_type = await self.topic_type(topic)
        if not msg_type:
            raise DeviceError(
                f"{self.bridge.instance}: no topic {topic} on the robot (see list_topics); "
                "to publish on a new topic give its msg_type"
            )
        return msg_type

    async def publishers(self, topic: str) -> list[str]:
        """Nodes publishing ``topic``."""
        return list((await self._call("publishers", topic=topic)).get("publishers", []))

    async def subscribers(self, topic: str) -> list[str]:
        """Nodes subscribed to ``topic``."""
        return list((await self._call("subscribers", topic=topic)).get("subscribers", []))

    # Services

    async def services(self) -> list[str]:
        """Every service name."""
        return sorted((await self._call("services")).get("services", []))

    async def service_type(self, service: str) -> str:
        """The service's type, or "" when it does not exist."""
        try:
            return str((await self._call("service_type", service=service)).get("type") or "")
        except ServiceCallFailed:
            return ""

    async def service_node(self, service: str) -> str:
        """The node providing ``service``, or "" when rosapi cannot tell."""
        try:
            return str((await self._call("service_node", service=service)).get("node") or "")
        except ServiceCallFailed:
            return ""

    # Actions

    async def action_servers(self) -> list[str]:
        """Every action that has a server."""
        return sorted((await self._call("action_servers")).get("action_servers", []))

    async def action_type(self, action: str) -> str:
        """The action's type, or "" when rosapi cannot tell (older rosapi has no action_type)."""
        try:
            return str((await self._call("action_type", action=action)).get("type") or "")
        except ServiceCallFailed:
            return ""

    # Nodes

    async def nodes(self) -> list[str]:
        """Every node name."""
        return sorted((await self._call("nodes")).get("nodes", []))

    async def node_details(self, node: str) -> dict[str, list[str]]:
        """What ``node`` publishes, subscribes to, and serves."""
        try:
            answer = await self._call("node_details", node=node)
        except ServiceCallFailed:
            raise DeviceError(
                f"{self.bridge.instance}: no node {node} on the robot (see list_nodes)"
            ) from None
        return {key: sorted(answer.get(key, [])) for key in ("publishing", "subscribing", "services")}

    # Parameters

    async def param_names(self) -> list[str]:
        """Every parameter, as ``/node:param``."""
        return sorted((await self._call("get_param_names")).get("names", []))

    async def get_param(self, name: str) -> Any:
        """A parameter's value; :class:`DeviceError` when it does not exist."""
        answer = await self._call("get_param", name=name, default_value="")
        if answer.get("successful") is False or answer.get("value", "") == "":
            reason = answer.get("reason") or "it does not exist"
            raise DeviceError(
                f"{self.bridge.instance}: cannot read parameter {name}: {reason} (see list_params)"
            )
        return json.loads(answer["value"])

    async def set_param(self, name: str, value: Any) -> None:
        """Set a parameter; :class:`DeviceError` with the node's reason when it refuses."""
        answer = await self._call("set_param", name=name, value=json.dumps(value))
        if answer.get("successful") is False:
            raise DeviceError(
                f"{self.bridge.instance}: the robot refused {name} = {value!r}: {answer.get('reason')}"
            )

    async def delete_param(self, name: str) -> None:
        """Delete (undeclare) a parameter."""
        answer = await self._call("delete_param", name=name)
        if answer.get("successful") is False:
            raise DeviceError(f"{self.bridge.instance}: cannot delete {name}: {answer.get('reason')}")

    async def has_param(self, name: str) -> bool:
        """Whether parameter ``name`` (``/node:param``) exists."""
        return bool((await self._call("has_param", name=name)).get("exists"))

    # Interface definitions (rosapi_msgs/TypeDef lists: the type first, then its nested types)

    async def message_details(self, msg_type: str) -> list[dict[str, Any]]:
        """The typedefs of a message type; :class:`DeviceError` when the robot does not know it."""
        return await self._typedefs("message_details", msg_type, "message")

    async def service_details(self, srv_type: str) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
        """The typedefs of a service type's request and response."""
        return await asyncio.gather(
            self._typedefs("service_request_details", srv_type, "service"),
            self._typedefs("service_response_details", srv_type, "service"),
        )

    async def action_details(self, action_type: str) -> list[list[dict[str, Any]]]:
        """The typedefs of an action type's goal, result and feedback.

        Newer rosapi has ``action_{goal,result,feedback}_details``; an older one still describes the
        generated ``<Action>_Goal``/``_Result``/``_Feedback`` messages through ``message_details``.
        """
        parts = ("goal", "result", "feedback")
        try:
            return list(
                await asyncio.gather(
                    *(self._typedefs(f"action_{part}_details", action_type, "action") for part in parts)
                )
            )
        except ServiceCallFailed:
            return list(
                await asyncio.gather(
                    *(
                        self._typedefs("message_details", f"{action_type}_{part.capitalize()}", "action")
                        for part in parts
                    )
                )
            )

    async def _typedefs(self, rosapi_service: str, type_name: str, kind: str) -> list[dict[str, Any]]:
        try:
            answer = await self._call(rosapi_service, type=type_name)
        except ServiceCallFailed as failure:
            if rosapi_service.startswith("action_") and "does not exist" in str(failure):
                raise  # an older rosapi: action_details falls back to message_details
            raise DeviceError(
                f"{self.bridge.instance}: the robot does not know the {kind} type {type_name} ({failure}); "
                f"check the spelling (package/{'msg' if kind == 'message' else 'srv' if kind == 'service' else 'action'}/Name)"
            ) from None
        typedefs = list(answer.get("typedefs") or [])
        if not typedefs:
            raise DeviceError(f"{self.bridge.instance}: the robot has no definition of {type_name}")
        return typedefs
