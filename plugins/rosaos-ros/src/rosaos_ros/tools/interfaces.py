"""Tools a model needs to drive a robot it does not know: interface schemas, parameter details,
and the status of action goals whoever sent them.

Schemas come from rosapi (``message_details``, ``service_request_details``/``_response_details``,
``action_*_details``), turned into nested fields with an example message by
:mod:`rosaos_ros.interfaces`.
"""

from __future__ import annotations

import base64
from typing import Annotated, Any

from fastmcp import FastMCP
from pydantic import Field

from rosaos.drivers import DeviceError
from rosaos_ros.backend import RosBackend
from rosaos_ros.goals import STATUS_NAMES
from rosaos_ros.interfaces import structure
from rosaos_ros.messages import normalize_type
from rosaos_ros.tools import READ_ONLY, ActionName, ParamName

GOAL_STATUS_ARRAY = "action_msgs/msg/GoalStatusArray"

TypeOrName = Annotated[
    str,
    Field(
        min_length=1,
        max_length=256,
        pattern=r"^(/[A-Za-z0-9_/~]*|[A-Za-z0-9_]+/((msg|srv|action)/)?[A-Za-z0-9_]+)$",
        description=(
            "An interface type such as geometry_msgs/msg/Twist, or the name of what uses it "
            "(a topic such as /cmd_vel, a service, an action): its type is looked up."
        ),
    ),
]


def register(mcp: FastMCP, backend: RosBackend) -> None:
    """Add the interface, parameter-detail and action-status tools."""
    rosapi = backend.rosapi

    @mcp.tool(annotations=READ_ONLY)
    async def message_details(msg_type: TypeOrName) -> dict[str, Any]:
        """Show every field of a message type, nested types spelled out, with an example message.

        Look a type up here before you publish a message you have not seen: copy ``example``,
        change the values you need, and publish that. Give a type (geometry_msgs/msg/Twist) or a
        topic (/cmd_vel).
        """
        topic = msg_type if msg_type.startswith("/") else None
        if topic is not None:
            msg_type = await rosapi.require_topic_type(topic)
        described = structure(await rosapi.message_details(msg_type))
        return {"topic": topic, **described} if topic else described

    @mcp.tool(annotations=READ_ONLY)
    async def service_details(service_type: TypeOrName) -> dict[str, Any]:
        """Show every field of a service type's request and response, with example messages.

        Look a service up here before call_service: the request's ``example`` is a valid request
        to fill in. Give a type (std_srvs/srv/Trigger) or a service name (/e_stop).
        """
        service = service_type if service_type.startswith("/") else None
        if service is not None:
            service_type = await rosapi.service_type(service)
            if not service_type:
                raise DeviceError(f"no service {service} on the robot; list_services shows them")
        request, response = await rosapi.service_details(service_type)
        report = {"type": normalize_type(service_type), "request": structure(request)}
        report["response"] = structure(response)
        return {"service": service, **report} if service else report

    @mcp.tool(annotations=READ_ONLY)
    async def action_details(action_type: TypeOrName) -> dict[str, Any]:
        """Show every field of an action type's goal, result and feedback, with examples.

        Look an action up here before send_goal: the goal's ``example`` is a valid goal to fill
        in. Give a type (irobot_create_msgs/action/Dock) or an action name (/dock).
        """
        action = action_type if action_type.startswith("/") else None
        if action is not None:
            action_type = await rosapi.action_type(action)
            if not action_type:
                raise DeviceError(
                    f"cannot tell the type of action {action}; list_actions shows the actions and their types"
                )
        goal, result, feedback = await rosapi.action_details(action_type)
        report = {
            "type": normalize_type(action_type),
            "goal": structure(goal),
            "result": structure(result),
            "feedback": structure(feedback),
        }
        return {"action": action, **report} if action else report

    @mcp.tool(annotations=READ_ONLY)
    async def has_param(name: ParamName) -> dict[str, Any]:
        """Tell whether a parameter ('/node:name') exists, without failing when it does not."""
        return {"name": name, "exists": await rosapi.has_param(name)}

    @mcp.tool(annotations=READ_ONLY)
    async def param_details(name: ParamName) -> dict[str, Any]:
        """Show a parameter's node, value, value type, and whether this instance may set it."""
        node = name.partition(":")[0]
        if not await rosapi.has_param(name):
            raise DeviceError(f"no parameter {name}; list_params(node={node!r}) shows that node's")
        value = await rosapi.get_param(name)
        try:
            backend.policy.check("params", name)
            settable = True
        except DeviceError:
            settable = False
        return {"name": name, "node": node, "value": value, "type": _value_type(value), "settable": settable}

    @mcp.tool(annotations=READ_ONLY)
    async def action_status(
        action: ActionName,
        timeout: Annotated[float, Field(gt=0, le=10, description="Seconds to wait for the status.")] = 2.0,
    ) -> dict[str, Any]:
        """Report the recent goals of an action, whoever sent them (another node, a person, us).

        Reads the action's own status topic; ``active`` counts goals still accepted or executing.
        Use goal_status for the goals send_goal sent.
        """
        if action not in await rosapi.action_servers():
            raise DeviceError(f"no action server {action} on the robot; list_actions shows them")
        topic = f"{action.rstrip('/')}/_action/status"
        messages = await backend.bridge.collect(topic, GOAL_STATUS_ARRAY, count=1, duration=timeout)
        goals = [_goal(status) for status in (messages[0].get("status_list") or [])] if messages else []
        return {
            "action": action,
            "goals": goals,
            "active": sum(goal["status"] in ("accepted", "executing", "canceling") for goal in goals),
        }


def _value_type(value: Any) -> str:
    """The ROS 2 parameter type of a JSON value (bool, integer, double, string, or an array of one)."""
    if isinstance(value, list):
        return f"{_value_type(value[0]) if value else 'unknown'}_array"
    if isinstance(value, bool):
        return "bool"
    return {int: "integer", float: "double", str: "string"}.get(type(value), type(value).__name__)


def _goal(status: dict[str, Any]) -> dict[str, Any]:
    """One ``action_msgs/GoalStatus`` for the model: goal id as hex, status by name, accepted time."""
    info = status.get("goal_info") or {}
    raw = (info.get("goal_id") or {}).get("uuid", "")
    try:
        goal_id = base64.b64decode(raw).hex() if isinstance(raw, str) else bytes(raw).hex()
    except (ValueError, TypeError):
        goal_id = str(raw)
    stamp = info.get("stamp") or {}
    return {
        "goal_id": goal_id,
        "status": STATUS_NAMES.get(int(status.get("status", 0)), "unknown"),
        "accepted_at": float(stamp.get("sec", 0)) + float(stamp.get("nanosec", 0)) / 1e9,
    }
