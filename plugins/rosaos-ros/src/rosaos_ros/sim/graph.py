"""The simulated ROS graph: nodes, topics, services, actions and parameters, plus ``/rosapi``.

Simulated nodes register what they publish, subscribe to, serve and declare; rosbridge clients
appear as the ``/rosbridge_websocket`` node, as with the real rosbridge. The ``/rosapi/*``
services answer introspection from this registry, in the shapes of ``rosapi_msgs``.
"""

from __future__ import annotations

import base64
import json
import uuid
from collections import Counter
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

from rosaos_ros.messages import normalize_type, stamp
from rosaos_ros.sim import interfaces

ROSAPI_NODE = "/rosapi"
BRIDGE_NODE = "/rosbridge_websocket"
GOAL_STATUS_KEEP = 10
"""Goals listed in an action's status topic (the newest ones)."""

Message = dict[str, Any]

ServiceHandler = Callable[[Message], Awaitable[Message]]
Listener = Callable[[Message], None]


class ServiceFailure(Exception):
    """A service call that failed; the message is what the caller reads."""


class ActionAborted(Exception):
    """Raised by a simulated action server that gives up; ``result`` is sent with status ABORTED."""

    def __init__(self, result: Message) -> None:
        super().__init__("aborted")
        self.result = result


class TopicTypeConflict(Exception):
    """A topic used with a type other than the one it has."""


@dataclass
class ActionGoal:
    """One goal handed to a simulated action server."""

    goal: Message
    feedback: Callable[[Message], None]
    """Send one feedback message to the client that sent the goal."""


@dataclass
class ActionServer:
    """A simulated action server: ``handler`` runs a goal to its result; it is cancelled on cancel."""

    type: str
    node: str
    handler: Callable[[ActionGoal], Awaitable[Message]]
    result_on_cancel: Callable[[], Message] = dict


@dataclass
class ServiceEntry:
    type: str
    node: str
    handler: ServiceHandler


@dataclass
class TopicEntry:
    type: str
    publishers: set[str] = field(default_factory=set)
    subscribers: set[str] = field(default_factory=set)


class RosGraph:
    """Everything a rosbridge client can see and reach in the simulated robot."""

    def __init__(self) -> None:
        self.nodes: set[str] = {ROSAPI_NODE, BRIDGE_NODE}
        self.topics: dict[str, TopicEntry] = {}
        self.services: dict[str, ServiceEntry] = {}
        self.actions: dict[str, ActionServer] = {}
        self.params: dict[str, dict[str, Any]] = {}
        self.bridge_fanout: Callable[[str, Message], None] | None = None
        """Set by the server: delivers a message to the rosbridge clients subscribed to the topic."""
        self._listeners: dict[str, list[Listener]] = {}
        self._bridge_subscriptions: Counter[str] = Counter()
        self._bridge_publishers: Counter[str] = Counter()
        self.latched: dict[str, Message] = {}
        """The last message of each transient-local topic (action status), for late subscribers."""
        self._goal_statuses: dict[str, dict[str, Message]] = {}
        self._add_rosapi()

    # Registration by simulated nodes

    def add_node(self, node: str, params: dict[str, Any] | None = None) -> None:
        """Declare a node and its parameters."""
        self.nodes.add(node)
        self.params.setdefault(node, {}).update(params or {})

    def add_publisher(self, topic: str, msg_type: str, node: str) -> None:
        """``node`` publishes ``topic``."""
        self._topic(topic, msg_type).publishers.add(node)

    def add_subscriber(self, topic: str, msg_type: str, node: str, listener: Listener) -> None:
        """``node`` subscribes to ``topic``; ``listener`` gets every message published on it."""
        self._topic(topic, msg_type).subscribers.add(node)
        self._listeners.setdefault(topic, []).append(listener)

    def add_service(self, name: str, srv_type: str, node: str, handler: ServiceHandler) -> None:
        """``node`` serves ``name``."""
        self.services[name] = ServiceEntry(normalize_type(srv_type), node, handler)

    def remove_service(self, name: str) -> None:
        """Forget a service (a rosbridge client stopped providing it)."""
        self.services.pop(name, None)

    def add_action(self, name: str, server: ActionServer) -> None:
        """``server.node`` serves action ``name``."""
        self.actions[name] = server

    def report_goal_status(self, action: str, goal_key: str, status: int) -> None:
        """A goal of ``action`` changed status: publish ``<action>/_action/status``, as servers do.

        ``goal_key`` is unique per goal; its UUID is derived from it. The list keeps the
        :data:`GOAL_STATUS_KEEP` most recent goals, and is latched for late subscribers.
        """
        goals = self._goal_statuses.setdefault(action, {})
        entry = goals.pop(goal_key, None) or {
            "goal_info": {
                "goal_id": {
                    "uuid": base64.b64encode(uuid.uuid5(uuid.NAMESPACE_URL, goal_key).bytes).decode()
                },
                "stamp": stamp(),
            }
        }
        goals[goal_key] = {**entry, "status": status}
        while len(goals) > GOAL_STATUS_KEEP:
            goals.pop(next(iter(goals)))
        topic = f"{action}/_action/status"
        self.latched[topic] = {"status_list": list(goals.values())}
        self.publish(topic, self.latched[topic])

    # Traffic

    def publish(self, topic: str, msg: Message) -> None:
        """Deliver ``msg`` to every subscriber of ``topic``: simulated nodes and rosbridge clients."""
        for listener in self._listeners.get(topic, []):
            listener(msg)
        if self.bridge_fanout is not None:
            self.bridge_fanout(topic, msg)

    def has_bridge_subscribers(self, topic: str) -> bool:
        """True while a rosbridge client subscribes to ``topic`` (cameras only render then)."""
        return self._bridge_subscriptions[topic] > 0

    def bridge_subscribe(self, topic: str, msg_type: str | None) -> str:
        """A rosbridge client subscribes; returns the topic's type. Raises on an unknown or wrong type."""
        entry = self.topics.get(topic)
        if entry is None and not msg_type:
            raise TopicTypeConflict(
                f"Cannot infer topic type for topic {topic} as it is not yet advertised; give its type"
            )
        entry = self._topic(topic, msg_type or (entry.type if entry else ""))
        self._bridge_subscriptions[topic] += 1
        entry.subscribers.add(BRIDGE_NODE)
        return entry.type

    def bridge_unsubscribe(self, topic: str) -> None:
        """A rosbridge client subscription ended."""
        self._bridge_subscriptions[topic] -= 1
        if self._bridge_subscriptions[topic] <= 0:
            del self._bridge_subscriptions[topic]
            if topic in self.topics:
                self.topics[topic].subscribers.discard(BRIDGE_NODE)

    def bridge_advertise(self, topic: str, msg_type: str | None) -> str:
        """A rosbridge client advertises (or publishes without advertising); returns the type."""
        entry = self.topics.get(topic)
        if entry is None and not msg_type:
            raise TopicTypeConflict(
                f"Cannot infer topic type for topic {topic} as it is not yet advertised; advertise it with a type"
            )
        entry = self._topic(topic, msg_type or (entry.type if entry else ""))
        self._bridge_publishers[topic] += 1
        entry.publishers.add(BRIDGE_NODE)
        return entry.type

    def bridge_unadvertise(self, topic: str) -> None:
        """A rosbridge client stopped publishing ``topic``."""
        self._bridge_publishers[topic] -= 1
        if self._bridge_publishers[topic] <= 0:
            del self._bridge_publishers[topic]
            if topic in self.topics:
                self.topics[topic].publishers.discard(BRIDGE_NODE)

    async def call_service(self, name: str, args: Message) -> Message:
        """Call a service; :class:`ServiceFailure` when it does not exist or fails."""
        entry = self.services.get(name)
        if entry is None:
            raise ServiceFailure(f"Service {name} does not exist")
        return await entry.handler(args)

    def _topic(self, topic: str, msg_type: str) -> TopicEntry:
        wanted = normalize_type(msg_type)
        entry = self.topics.get(topic)
        if entry is None:
            entry = self.topics[topic] = TopicEntry(wanted)
        elif wanted and normalize_type(entry.type) != wanted:
            raise TopicTypeConflict(f"Topic {topic} has type {entry.type}, not {msg_type}")
        return entry

    # /rosapi

    def _add_rosapi(self) -> None:
        def service(name: str, handler: Callable[[Message], Message]) -> None:
            async def call(args: Message) -> Message:
                return handler(args)

            srv = "".join(part.capitalize() for part in name.split("_"))
            self.add_service(f"/rosapi/{name}", f"rosapi_msgs/srv/{srv}", ROSAPI_NODE, call)

        service("topics", lambda _: self._topics_and_types())
        service("topic_type", lambda a: {"type": self._entry(a.get("topic")).type})
        service("topics_for_type", lambda a: {"topics": self._topics_of_type(a.get("type", ""))})
        service("publishers", lambda a: {"publishers": sorted(self._entry(a.get("topic")).publishers)})
        service("subscribers", lambda a: {"subscribers": sorted(self._entry(a.get("topic")).subscribers)})
        service("services", lambda _: {"services": sorted(self.services)})
        service("service_type", lambda a: {"type": self._service(a.get("service")).type})
        service("service_node", lambda a: {"node": self._service(a.get("service")).node})
        service("services_for_type", lambda a: {"services": self._services_of_type(a.get("type", ""))})
        service("nodes", lambda _: {"nodes": sorted(self.nodes)})
        service("node_details", lambda a: self._node_details(str(a.get("node", ""))))
        service("action_servers", lambda _: {"action_servers": sorted(self.actions)})
        service("action_type", lambda a: {"type": self._action_type(str(a.get("action", "")))})
        service("get_param_names", lambda _: {"names": self._param_names()})
        service("get_param", self._get_param)
        service("has_param", lambda a: {"exists": self._has_param(str(a.get("name", "")))})
        service("set_param", self._set_param)
        service("delete_param", self._delete_param)
        service("get_time", lambda _: {"time": stamp()})
        service("get_ros_version", lambda _: {"version": 2, "distro": "humble"})
        service("message_details", lambda a: self._typedefs(a.get("type"), ""))
        service("service_request_details", lambda a: self._typedefs(a.get("type"), "_Request"))
        service("service_response_details", lambda a: self._typedefs(a.get("type"), "_Response"))
        service("action_goal_details", lambda a: self._typedefs(a.get("type"), "_Goal"))
        service("action_result_details", lambda a: self._typedefs(a.get("type"), "_Result"))
        service("action_feedback_details", lambda a: self._typedefs(a.get("type"), "_Feedback"))

    def _typedefs(self, type_name: Any, suffix: str) -> Message:
        try:
            return {"typedefs": interfaces.typedefs(f"{type_name or ''}{suffix}")}
        except interfaces.UnknownInterface as unknown:
            raise ServiceFailure(str(unknown)) from None

    def _topics_and_types(self) -> Message:
        names = sorted(self.topics)
        return {"topics": names, "types": [self.topics[name].type for name in names]}

    def _entry(self, topic: Any) -> TopicEntry:
        return self.topics.get(str(topic), TopicEntry(""))

    def _service(self, name: Any) -> ServiceEntry:
        entry = self.services.get(str(name))
        if entry is None:
            raise ServiceFailure(f"Service {name} does not exist")
        return entry

    def _action_type(self, name: str) -> str:
        server = self.actions.get(name)
        return server.type if server else ""

    def _topics_of_type(self, msg_type: str) -> list[str]:
        wanted = normalize_type(msg_type)
        return sorted(name for name, entry in self.topics.items() if normalize_type(entry.type) == wanted)

    def _services_of_type(self, srv_type: str) -> list[str]:
        wanted = normalize_type(srv_type)
        return sorted(name for name, entry in self.services.items() if entry.type == wanted)

    def _node_details(self, node: str) -> Message:
        if node not in self.nodes:
            raise ServiceFailure(f"Node {node} does not exist")
        return {
            "subscribing": sorted(t for t, e in self.topics.items() if node in e.subscribers),
            "publishing": sorted(t for t, e in self.topics.items() if node in e.publishers),
            "services": sorted(s for s, e in self.services.items() if e.node == node),
        }

    # Parameters are named "/node:param", as rosapi does for ROS 2.

    def _param_names(self) -> list[str]:
        return sorted(f"{node}:{name}" for node, params in self.params.items() for name in params)

    def _split(self, full_name: str) -> tuple[str, str]:
        node, _, name = full_name.partition(":")
        if not name:
            raise ServiceFailure(f"parameter name {full_name!r} must be '/node:param'")
        return node, name

    def _has_param(self, full_name: str) -> bool:
        node, _, name = full_name.partition(":")
        return name in self.params.get(node, {})

    def _get_param(self, args: Message) -> Message:
        node, name = self._split(str(args.get("name", "")))
        if name not in self.params.get(node, {}):
            default = args.get("default_value") or ""
            return {
                "value": default,
                "successful": False,
                "reason": f"Parameter {node}:{name} does not exist",
            }
        return {"value": json.dumps(self.params[node][name]), "successful": True, "reason": ""}

    def _set_param(self, args: Message) -> Message:
        node, name = self._split(str(args.get("name", "")))
        try:
            value = json.loads(str(args.get("value", "")))
        except ValueError:
            return {"successful": False, "reason": "the value must be a JSON-formatted string"}
        if node not in self.nodes:
            return {"successful": False, "reason": f"Node {node} does not exist"}
        params = self.params.setdefault(node, {})
        if name not in params:
            return {"successful": False, "reason": f"Parameter {name} is not declared on {node}"}
        current = params[name]
        if isinstance(current, float) and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if type(value) is not type(current):
            return {
                "successful": False,
                "reason": f"Parameter {node}:{name} is a {type(current).__name__}, not a {type(value).__name__}",
            }
        params[name] = value
        return {"successful": True, "reason": ""}

    def _delete_param(self, args: Message) -> Message:
        node, name = self._split(str(args.get("name", "")))
        if self.params.get(node, {}).pop(name, None) is None:
            return {"successful": False, "reason": f"Parameter {node}:{name} does not exist"}
        return {"successful": True, "reason": ""}
