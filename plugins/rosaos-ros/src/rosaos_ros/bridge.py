"""One rosbridge connection through roslibpy, used from the device server's asyncio loop.

roslibpy runs its WebSocket client (Autobahn) on a loop of its own in a background thread and
calls back from there. This class hands every callback to the owner loop, and turns each
request into an asyncio future that is bounded by a timeout *and* failed at once when the
connection drops. So no tool ever hangs on a robot that went away, and no call waits on a
blocking roslibpy method.

roslibpy's asyncio transport is used rather than its Twisted one: its loop is an ordinary,
restartable asyncio loop (the Twisted reactor cannot be restarted in a process), with the same
Autobahn WebSocket stack. roslibpy reconnects by itself with exponential backoff (0.5 s, growing
to 10 s here); WebSocket pings every 2 s notice a silent network loss within about 5 s.

Guard: roslibpy queues a message sent while disconnected and sends it on reconnection; a stale
velocity command must never be replayed, so every send checks the connection first.
"""

from __future__ import annotations

import asyncio
import logging
import threading
import time
from collections import deque
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any, TypeVar

import roslibpy

from rosaos.drivers import DeviceError

log = logging.getLogger("rosaos_ros.bridge")

T = TypeVar("T")
Message = dict[str, Any]
Listener = Callable[[Message], None]

RECONNECT_INITIAL_DELAY = 0.5
RECONNECT_MAX_DELAY = 10.0
PING_INTERVAL = 2.0
PING_TIMEOUT = 3.0
_CREATE_LOCK = threading.Lock()


class ServiceCallFailed(DeviceError):
    """The robot answered a service call with a failure (the service exists but refused or broke)."""


@dataclass
class GoalHandle:
    """A goal sent to an action server: its feedback arrives in ``feedback``, its end in ``result``."""

    goal_id: str
    action: str
    action_type: str
    result: asyncio.Future[tuple[int, Any]]
    """Resolves to ``(GoalStatus value, result values)``; fails if the goal is refused or the link drops."""
    feedback: asyncio.Queue[Message] = field(default_factory=asyncio.Queue)
    client: Any = None

    def cancel(self) -> None:
        """Ask the action server to cancel the goal (the result then says CANCELED)."""
        if self.client is not None and not self.result.done():
            self.client.cancel_goal(self.goal_id)


@dataclass
class _Fanout:
    """One roslibpy subscription per topic, shared by every local listener of that topic.

    roslibpy keys its callbacks by topic name and drops them all on unsubscribe, so two
    roslibpy subscriptions to one topic would cut each other off.
    """

    topic: Any
    listeners: set[Listener] = field(default_factory=set)


class RosbridgeClient:
    """A rosbridge connection for one robot instance."""

    def __init__(
        self,
        instance: str,
        host: str,
        port: int,
        *,
        secure: bool = False,
        token: str | None = None,
        call_timeout: float = 10.0,
    ) -> None:
        self.instance = instance
        self.host = host
        self.port = port
        self.secure = secure
        self.token = token
        self.call_timeout = call_timeout
        self.connected = False
        self.disconnected_since: float | None = None
        self.statuses: deque[Message] = deque(maxlen=20)
        """The last ``status`` messages rosbridge sent (errors about our requests)."""
        self._on_disconnect: list[Callable[[DeviceError], None]] = []
        self._ros: Any = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._ready = asyncio.Event()
        self._closed = False
        self._lost_waiters: set[asyncio.Future[None]] = set()
        self._fanouts: dict[str, _Fanout] = {}
        self._publishers: dict[tuple[str, str], Any] = {}

    @property
    def url(self) -> str:
        return f"{'wss' if self.secure else 'ws'}://{self.host}:{self.port}"

    def on_disconnect(self, callback: Callable[[DeviceError], None]) -> None:
        """Call ``callback`` (on the owner loop) with the error to report whenever the connection drops."""
        self._on_disconnect.append(callback)

    # Lifecycle

    async def connect(self, timeout: float) -> None:
        """Connect, waiting up to ``timeout`` s; :class:`DeviceError` says how to fix an unreachable robot."""
        self._loop = asyncio.get_running_loop()
        self._ros = await asyncio.to_thread(self._create)
        try:
            await asyncio.wait_for(self._ready.wait(), timeout)
        except TimeoutError:
            await self.close()
            raise DeviceError(
                f"{self.instance}: cannot reach rosbridge at {self.url} within {timeout:g} s. Check that the robot "
                "is on and on this network, and that rosbridge runs on it "
                "(ros2 launch rosbridge_server rosbridge_websocket_launch.xml); "
                f"fix host/rosbridge_port in [devices.{self.instance}] if they are wrong"
            ) from None

    def _create(self) -> Any:
        headers = {"Authorization": f"Bearer {self.token}"} if self.token else None
        # roslibpy starts its one background loop per process lazily, and that start is not
        # thread-safe: two instances connecting at once (turtlebot and dog in one process)
        # would collide. The lock makes the creations take turns; connecting stays concurrent.
        with _CREATE_LOCK:
            ros = roslibpy.Ros(
                self.host, self.port, is_secure=self.secure, headers=headers, transport="asyncio"
            )
        factory = ros.factory
        factory.initialDelay = RECONNECT_INITIAL_DELAY
        factory.maxDelay = RECONNECT_MAX_DELAY
        factory.setProtocolOptions(autoPingInterval=PING_INTERVAL, autoPingTimeout=PING_TIMEOUT)
        ros.on("ready", self._ready_in_thread)
        ros.on("close", self._closed_in_thread)
        # In case it connected before the listener was added. A lambda, not the method itself:
        # roslibpy keys listeners by function, so a one-shot of the same function would replace
        # the permanent one above, and reconnections would go unnoticed.
        factory.on_ready(lambda proto: self._ready_in_thread(proto))
        return ros

    async def close(self) -> None:
        """Disconnect for good; pending calls fail, reconnection stops."""
        self._closed = True
        ros, self._ros = self._ros, None
        self._mark_lost("the driver is shutting down")
        if ros is None:
            return
        ros.factory.maxRetries = 0  # a reconnection already scheduled gives up
        # Not ros.close(): it can block for 10 s when the link drops at the same moment. This
        # closes now if connected, or as soon as a last reconnection lands; it never waits.
        ros.factory.on_ready(lambda proto: proto.send_close())

    # Connection state (callbacks arrive on roslibpy's thread)

    def _ready_in_thread(self, proto: Any) -> None:
        if self._closed:
            proto.send_close()
            return
        # roslibpy has no handler for rosbridge's "status" op and logs each one as an error.
        proto._message_handlers["status"] = self._status_in_thread
        self._call_soon(self._mark_ready)

    def _closed_in_thread(self, _proto: Any) -> None:
        self._call_soon(self._mark_lost, "the connection to rosbridge dropped")

    def _status_in_thread(self, message: Message) -> None:
        self._call_soon(self._record_status, dict(message))

    def _call_soon(self, callback: Callable[..., None], *args: Any) -> None:
        loop = self._loop
        if loop is not None and not loop.is_closed():
            loop.call_soon_threadsafe(callback, *args)

    def _mark_ready(self) -> None:
        if self.connected:
            return
        if self.disconnected_since is not None:
            log.warning("%s: reconnected to rosbridge at %s", self.instance, self.url)
        self.connected = True
        self.disconnected_since = None
        self._ready.set()

    def _mark_lost(self, reason: str) -> None:
        was_connected = self.connected
        self.connected = False
        self._ready.clear()
        if self.disconnected_since is None:
            self.disconnected_since = time.time()
        error = DeviceError(
            f"{self.instance}: {reason} ({self.url}) during the call; the driver reconnects by itself. "
            "Check the robot and its network, then try again"
        )
        for waiter in list(self._lost_waiters):
            if not waiter.done():
                waiter.set_exception(error)
        if was_connected and not self._closed:
            log.warning("%s: lost rosbridge at %s; reconnecting with backoff", self.instance, self.url)
            for callback in self._on_disconnect:
                callback(error)

    def _record_status(self, message: Message) -> None:
        self.statuses.append(message)
        log.info("%s: rosbridge %s: %s", self.instance, message.get("level"), message.get("msg"))

    def check(self) -> None:
        """Raise :class:`DeviceError` at once while the robot is unreachable."""
        if self.connected and self._ros is not None:
            return
        if self._closed:
            raise DeviceError(f"{self.instance}: the ROS driver is shut down")
        since = time.strftime("%H:%M:%S", time.localtime(self.disconnected_since or time.time()))
        raise DeviceError(
            f"{self.instance}: the robot is unreachable: no rosbridge connection to {self.url} since {since} "
            "(reconnecting with backoff). Check that the robot is on and rosbridge runs "
            "(ros2 launch rosbridge_server rosbridge_websocket_launch.xml), then try again in a few seconds"
        )

    async def guarded(self, work: Awaitable[T], timeout: float | None, what: str) -> T:
        """Await ``work`` for at most ``timeout`` s, failing at once if the connection drops meanwhile."""
        assert self._loop is not None
        if not self.connected:
            if asyncio.iscoroutine(work):
                work.close()
            self.check()
        lost: asyncio.Future[None] = self._loop.create_future()
        self._lost_waiters.add(lost)
        task = asyncio.ensure_future(work)
        try:
            racers: set[asyncio.Future[Any]] = {task, lost}
            done, _ = await asyncio.wait(racers, timeout=timeout, return_when=asyncio.FIRST_COMPLETED)
            if task in done:
                return task.result()
            if lost in done:
                lost.result()  # raises the disconnection error
            raise DeviceError(
                f"{self.instance}: {what} got no answer within {timeout:g} s; the robot may be busy or the "
                "name wrong (check it with the list_* tools)"
            )
        finally:
            task.cancel()
            self._lost_waiters.discard(lost)
            if lost.done() and not lost.cancelled():
                lost.exception()  # retrieved: the task's own outcome was what mattered
            lost.cancel()

    # Requests

    async def call_service(
        self, name: str, args: Message | None = None, timeout: float | None = None
    ) -> Message:
        """Call a service; :class:`ServiceCallFailed` if the robot says it failed."""
        self.check()
        assert self._loop is not None
        loop, future = self._loop, self._loop.create_future()

        def answered(response: Any) -> None:
            loop.call_soon_threadsafe(_resolve, future, dict(response))

        def failed(values: Any) -> None:
            error = ServiceCallFailed(f"{self.instance}: service {name} failed: {values}")
            loop.call_soon_threadsafe(_reject, future, error)

        service = roslibpy.Service(self._ros, name, "")
        service.call(roslibpy.ServiceRequest(args or {}), answered, failed)
        result: Message = await self.guarded(future, timeout or self.call_timeout, f"service {name}")
        return result

    def subscribe(self, topic: str, msg_type: str | None, listener: Listener) -> Callable[[], None]:
        """Deliver every message on ``topic`` to ``listener`` (on the owner loop); returns the unsubscribe."""
        self.check()
        fanout = self._fanouts.get(topic)
        if fanout is None:
            handle = roslibpy.Topic(self._ros, topic, msg_type, queue_length=1)
            fanout = self._fanouts[topic] = _Fanout(handle)
            handle.subscribe(lambda message: self._call_soon(self._deliver, topic, dict(message)))
        fanout.listeners.add(listener)

        def unsubscribe() -> None:
            fanout.listeners.discard(listener)
            if not fanout.listeners and self._fanouts.get(topic) is fanout:
                del self._fanouts[topic]
                if self._ros is not None:
                    fanout.topic.unsubscribe()

        return unsubscribe

    def _deliver(self, topic: str, message: Message) -> None:
        fanout = self._fanouts.get(topic)
        for listener in list(fanout.listeners if fanout else ()):
            listener(message)

    async def collect(
        self, topic: str, msg_type: str | None, *, count: int, duration: float
    ) -> list[Message]:
        """Up to ``count`` messages from ``topic`` within ``duration`` s (fewer if fewer came)."""
        queue: asyncio.Queue[Message] = asyncio.Queue()
        unsubscribe = self.subscribe(topic, msg_type, queue.put_nowait)
        messages: list[Message] = []
        deadline = time.monotonic() + duration
        try:
            while len(messages) < count and (remaining := deadline - time.monotonic()) > 0:
                try:
                    messages.append(await self.guarded(queue.get(), remaining, f"topic {topic}"))
                except DeviceError:
                    if not self.connected:
                        raise
                    break  # the duration is over
        finally:
            unsubscribe()
        return messages

    def advertise(self, topic: str, msg_type: str) -> Any:
        """Become a publisher of ``topic`` (done once per topic and type; publish does it when needed)."""
        self.check()
        publisher = self._publishers.get((topic, msg_type))
        if publisher is None:
            publisher = self._publishers[(topic, msg_type)] = roslibpy.Topic(
                self._ros, topic, msg_type, queue_size=1
            )
            publisher.advertise()
        return publisher

    def publish(self, topic: str, msg_type: str, message: Message) -> None:
        """Publish one message. Safe from any thread once the topic is advertised (the deadman's watchdog uses it)."""
        self.advertise(topic, msg_type).publish(roslibpy.Message(message))

    def send_goal(self, action: str, action_type: str, goal: Message) -> GoalHandle:
        """Send a goal; its feedback and result arrive on the returned handle."""
        self.check()
        assert self._loop is not None
        loop = self._loop
        result: asyncio.Future[tuple[int, Any]] = loop.create_future()
        client = roslibpy.ActionClient(self._ros, action, action_type)
        handle = GoalHandle("", action, action_type, result, client=client)

        def finished(outcome: Any) -> None:
            status = outcome.get("status")
            value = getattr(status, "value", status)
            loop.call_soon_threadsafe(_resolve, result, (int(value or 0), outcome.get("values")))

        def refused(outcome: Any) -> None:
            error = DeviceError(f"{self.instance}: action {action} refused the goal: {outcome.get('values')}")
            loop.call_soon_threadsafe(_reject, result, error)

        def feedback(values: Any) -> None:
            loop.call_soon_threadsafe(handle.feedback.put_nowait, dict(values))

        handle.goal_id = client.send_goal(roslibpy.Goal(goal), finished, feedback, refused)
        lost: asyncio.Future[None] = loop.create_future()
        self._lost_waiters.add(lost)

        def on_lost(waiter: asyncio.Future[None]) -> None:
            self._lost_waiters.discard(waiter)
            if not waiter.cancelled() and (error := waiter.exception()) is not None:
                _reject(result, error)

        lost.add_done_callback(on_lost)
        result.add_done_callback(lambda _: lost.cancel())
        return handle


def _resolve(future: asyncio.Future[Any], value: Any) -> None:
    if not future.done():
        future.set_result(value)


def _reject(future: asyncio.Future[Any], error: BaseException) -> None:
    if not future.done():
        future.set_exception(error)
