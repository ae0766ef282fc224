"""One rosbridge client connection: the operations it sends, and what the simulator sends back."""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
from collections.abc import Awaitable, Callable
from typing import Any

from websockets.asyncio.server import ServerConnection
from websockets.exceptions import ConnectionClosed

from rosaos_ros.messages import normalize_type
from rosaos_ros.sim.graph import (
    BRIDGE_NODE,
    ActionAborted,
    ActionGoal,
    Message,
    RosGraph,
    ServiceFailure,
    TopicTypeConflict,
)
from rosaos_ros.sim.subscription import ClientSubscription

log = logging.getLogger("rosaos_ros.sim")

STATUS_LEVELS = {"info": 0, "warning": 1, "error": 2, "none": 3}
GOAL_EXECUTING, GOAL_SUCCEEDED, GOAL_CANCELED, GOAL_ABORTED, GOAL_UNKNOWN = 2, 4, 5, 6, 0


class ClientSession:
    """One rosbridge client connection."""

    def __init__(self, graph: RosGraph, connection: ServerConnection) -> None:
        self.graph = graph
        self.connection = connection
        self.subscriptions: dict[str, ClientSubscription] = {}
        self.advertised: dict[str, int] = {}
        self.provided: set[str] = set()
        self.goals: dict[str, asyncio.Task[None]] = {}
        self.level = STATUS_LEVELS["error"]
        self._outgoing: asyncio.Queue[str] = asyncio.Queue()
        self._sent = asyncio.Event()
        self._service_calls: dict[str, asyncio.Future[tuple[bool, Any]]] = {}
        self._tasks: set[asyncio.Task[None]] = set()
        self._call_counter = 0
        self._ops: dict[str, Callable[[Message], None]] = {
            "advertise": self._advertise,
            "unadvertise": self._unadvertise,
            "publish": self._publish,
            "subscribe": self._subscribe,
            "unsubscribe": self._unsubscribe,
            "call_service": lambda m: self._spawn(self._call_service(m)),
            "advertise_service": self._advertise_service,
            "unadvertise_service": self._unadvertise_service,
            "service_response": self._service_response,
            "send_action_goal": self._send_action_goal,
            "cancel_action_goal": self._cancel_action_goal,
            "set_level": self._set_level,
            "auth": lambda m: None,  # rosauth MACs are not checked; the simulator's token is
        }

    async def run(self) -> None:
        """Read operations until the client goes away."""
        writer = asyncio.get_running_loop().create_task(self._write())
        try:
            async for raw in self.connection:
                self._dispatch(raw)
        except ConnectionClosed:
            pass
        finally:
            writer.cancel()

    def send(self, message: Message) -> None:
        """Queue a message to the client."""
        self._outgoing.put_nowait(json.dumps(message))

    async def caught_up(self) -> None:
        """Return once at most one message waits for the socket (a slow client holds this up)."""
        while self._outgoing.qsize() > 1:
            self._sent.clear()
            await self._sent.wait()

    def status(self, level: str, msg: str, op_id: Any = None) -> None:
        """Send a ``status`` message if the client's level lets it through."""
        if STATUS_LEVELS[level] >= self.level:
            status: Message = {"op": "status", "level": level, "msg": msg}
            if op_id is not None:
                status["id"] = op_id
            self.send(status)

    def close(self) -> None:
        """The client is gone: drop its subscriptions, advertisements, services and goals."""
        for topic, subscription in self.subscriptions.items():
            subscription.cancel()
            for _ in subscription.ids:
                self.graph.bridge_unsubscribe(topic)
        self.subscriptions.clear()
        for topic, count in self.advertised.items():
            for _ in range(count):
                self.graph.bridge_unadvertise(topic)
        self.advertised.clear()
        for name in self.provided:
            self.graph.remove_service(name)
        for future in self._service_calls.values():
            future.cancel()
        for task in [*self.goals.values(), *self._tasks]:
            task.cancel()

    async def _write(self) -> None:
        with contextlib.suppress(ConnectionClosed):
            while True:
                await self.connection.send(await self._outgoing.get())
                self._sent.set()

    def _spawn(self, work: Awaitable[None]) -> None:
        task = asyncio.ensure_future(work)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    def _dispatch(self, raw: str | bytes) -> None:
        try:
            message = json.loads(raw)
        except ValueError:
            self.status("error", "Unable to load JSON message")
            return
        if not isinstance(message, dict):
            self.status("error", "A rosbridge message is a JSON object with an 'op'")
            return
        op = message.get("op")
        handler = self._ops.get(str(op))
        if handler is None:
            self.status("error", f"Unknown operation: {op}", message.get("id"))
            return
        try:
            handler(message)
        except KeyError as missing:
            self.status("error", f"{op}: Expected a {missing} field", message.get("id"))
        except (TopicTypeConflict, ServiceFailure, ValueError, TypeError) as error:
            self.status("error", f"{op}: {error}", message.get("id"))

    # Topics

    def _advertise(self, message: Message) -> None:
        topic = message["topic"]
        self.graph.bridge_advertise(topic, message.get("type"))
        self.advertised[topic] = self.advertised.get(topic, 0) + 1

    def _unadvertise(self, message: Message) -> None:
        topic = message["topic"]
        if self.advertised.get(topic):
            self.advertised[topic] -= 1
            self.graph.bridge_unadvertise(topic)

    def _publish(self, message: Message) -> None:
        topic, msg = message["topic"], message["msg"]
        if not isinstance(msg, dict):
            raise ValueError("msg must be a JSON object")
        if not self.advertised.get(topic):  # rosbridge advertises on first publish
            self._advertise({"topic": topic, "type": message.get("type")})
        self.graph.publish(topic, msg)

    def _subscribe(self, message: Message) -> None:
        topic = message["topic"]
        sub_id = str(message.get("id") or f"subscribe:{topic}")
        compression = message.get("compression") or "none"
        if compression != "none":
            self.status("warning", f"compression {compression!r} is not simulated; sending JSON", sub_id)
        subscription = self.subscriptions.get(topic)
        if subscription is None or sub_id not in subscription.ids:
            self.graph.bridge_subscribe(topic, message.get("type"))
        if subscription is None:
            subscription = self.subscriptions[topic] = ClientSubscription(self, topic)
        subscription.add(
            sub_id, int(message.get("throttle_rate") or 0), int(message.get("queue_length") or 0)
        )
        if topic in self.graph.latched:  # transient-local topics hand a late subscriber the last message
            subscription.offer(self.graph.latched[topic])

    def _unsubscribe(self, message: Message) -> None:
        topic = message["topic"]
        subscription = self.subscriptions.get(topic)
        if subscription is None:
            return
        sub_id = message.get("id")
        ids = (
            [str(sub_id)]
            if sub_id is not None and str(sub_id) in subscription.ids
            else list(subscription.ids)
        )
        for each in ids:
            del subscription.ids[each]
            self.graph.bridge_unsubscribe(topic)
        if not subscription.ids:
            subscription.cancel()
            del self.subscriptions[topic]

    # Services

    async def _call_service(self, message: Message) -> None:
        name, call_id = message["service"], message.get("id")
        args = message.get("args") or {}
        timeout = message.get("timeout")
        try:
            if not isinstance(args, dict):
                raise ServiceFailure("args must be a JSON object of request fields")
            values: Any = await asyncio.wait_for(self.graph.call_service(name, args), timeout or None)
            ok = True
        except ServiceFailure as error:
            values, ok = str(error), False
        except TimeoutError:
            values, ok = "Timeout exceeded while waiting for service response", False
        if not ok:
            self.status("error", f"call_service {name}: {values}", call_id)
        response: Message = {"op": "service_response", "service": name, "values": values, "result": ok}
        if call_id is not None:
            response["id"] = call_id
        self.send(response)

    def _advertise_service(self, message: Message) -> None:
        name, srv_type = message["service"], message["type"]

        async def forward(args: Message) -> Message:
            self._call_counter += 1
            call_id = f"service_request:{name}:{self._call_counter}"
            future: asyncio.Future[tuple[bool, Any]] = asyncio.get_running_loop().create_future()
            self._service_calls[call_id] = future
            self.send({"op": "call_service", "id": call_id, "service": name, "args": args})
            try:
                ok, values = await future
            except asyncio.CancelledError:
                raise ServiceFailure(f"the client providing {name} went away") from None
            finally:
                self._service_calls.pop(call_id, None)
            if not ok:
                raise ServiceFailure(str(values))
            return values if isinstance(values, dict) else {}

        self.graph.add_service(name, srv_type, BRIDGE_NODE, forward)
        self.provided.add(name)

    def _unadvertise_service(self, message: Message) -> None:
        name = message["service"]
        if name in self.provided:
            self.provided.discard(name)
            self.graph.remove_service(name)

    def _service_response(self, message: Message) -> None:
        future = self._service_calls.get(str(message.get("id")))
        if future is not None and not future.done():
            future.set_result((bool(message.get("result", True)), message.get("values")))

    # Actions

    def _send_action_goal(self, message: Message) -> None:
        goal_id = str(message.get("id") or f"send_action_goal:{message['action']}")
        task = asyncio.get_running_loop().create_task(self._run_goal(goal_id, message))
        self.goals[goal_id] = task
        task.add_done_callback(lambda _: self.goals.pop(goal_id, None))

    async def _run_goal(self, goal_id: str, message: Message) -> None:
        name = message["action"]
        server = self.graph.actions.get(name)
        if server is None:
            self._action_failure(goal_id, name, f"Action server {name} does not exist")
            return
        wanted = normalize_type(str(message.get("action_type", "")))
        if wanted != normalize_type(server.type):
            self._action_failure(goal_id, name, f"Action {name} has type {server.type}, not {wanted}")
            return
        want_feedback = bool(message.get("feedback", False))

        def feedback(values: Message) -> None:
            if want_feedback:
                self.send({"op": "action_feedback", "id": goal_id, "action": name, "values": values})

        args = message.get("args") or {}
        status_key = f"{id(self)}:{goal_id}"
        self.graph.report_goal_status(name, status_key, GOAL_EXECUTING)
        status = GOAL_ABORTED
        try:
            values = await server.handler(ActionGoal(args if isinstance(args, dict) else {}, feedback))
            status = GOAL_SUCCEEDED
        except asyncio.CancelledError:
            values, status = server.result_on_cancel(), GOAL_CANCELED
        except ActionAborted as aborted:
            values, status = aborted.result, GOAL_ABORTED
        except Exception as error:  # a simulated server's bug must reach the client, not kill the session
            log.exception("action %s failed", name)
            self._action_failure(goal_id, name, f"{type(error).__name__}: {error}")
            return
        finally:
            self.graph.report_goal_status(name, status_key, status)
        self.send(
            {
                "op": "action_result",
                "id": goal_id,
                "action": name,
                "values": values,
                "status": status,
                "result": True,
            }
        )

    def _action_failure(self, goal_id: str, name: str, reason: str) -> None:
        self.status("error", f"send_action_goal {name}: {reason}", goal_id)
        self.send(
            {
                "op": "action_result",
                "id": goal_id,
                "action": name,
                "values": reason,
                "status": GOAL_UNKNOWN,
                "result": False,
            }
        )

    def _cancel_action_goal(self, message: Message) -> None:
        task = self.goals.get(str(message.get("id")))
        if task is not None:
            task.cancel()

    def _set_level(self, message: Message) -> None:
        level = str(message.get("level", "error"))
        if level not in STATUS_LEVELS:
            raise ValueError(f"level must be one of {', '.join(STATUS_LEVELS)}")
        self.level = STATUS_LEVELS[level]
