"""The rosbridge v2 protocol over a real WebSocket server, on top of a :class:`RosGraph`.

Operations (JSON objects with an ``op``), as rosbridge_suite speaks them for ROS 2:

- topics: ``advertise``, ``unadvertise``, ``publish``, ``subscribe`` (``throttle_rate`` in ms,
  ``queue_length``), ``unsubscribe``; the server sends ``publish`` to subscribers;
- services: ``call_service`` answered by ``service_response``; a client may also provide a
  service (``advertise_service``, then it answers the ``call_service`` it is sent with its own
  ``service_response``), and ``unadvertise_service``;
- actions: ``send_action_goal`` answered by ``action_feedback`` messages and an ``action_result``
  (``status`` as in ``action_msgs/GoalStatus``); ``cancel_action_goal``;
- ``set_level``, and ``status`` messages (level, msg, id) when an operation fails.

A client's subscriptions, advertisements, services and goals end when it disconnects.

Who may connect: anything on the machine can reach a loopback port, and a web page in a browser
can open a WebSocket to one. A handshake that carries an ``Origin`` (every browser sends one) is
refused unless that origin was allowed, and with a ``token`` the client must send it
(``Authorization: Bearer`` or ``?token=``). The rosaOS ``sim`` backend always sets a fresh token.
"""

from __future__ import annotations

from collections.abc import Collection
from http import HTTPStatus
from urllib.parse import parse_qs, urlsplit

from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.http11 import Request, Response

from rosaos_ros.sim.graph import Message, RosGraph
from rosaos_ros.sim.session import ClientSession


class RosbridgeServer:
    """Serves one :class:`RosGraph` to any number of rosbridge clients."""

    def __init__(self, graph: RosGraph, token: str | None = None, origins: Collection[str] = ()) -> None:
        self.graph = graph
        self.token = token
        self.origins = frozenset(origin.rstrip("/") for origin in origins)
        """Browser origins allowed to connect (``http://localhost:8080``); none by default."""
        self.sessions: set[ClientSession] = set()
        self._server: Server | None = None
        graph.bridge_fanout = self._fanout

    async def start(self, host: str, port: int) -> int:
        """Listen on ``host:port`` (0 picks a free port); returns the port."""
        self._server = await serve(self._handle, host, port, process_request=self._authorize, max_size=2**24)
        return int(next(iter(self._server.sockets)).getsockname()[1])

    async def stop(self) -> None:
        """Close every connection and stop listening."""
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
            self._server = None

    def _authorize(self, connection: ServerConnection, request: Request) -> Response | None:
        origin = request.headers.get("Origin")
        if origin is not None and origin.rstrip("/") not in self.origins:
            return connection.respond(
                HTTPStatus.FORBIDDEN,
                f"rosbridge simulator: connections from the web page origin {origin!r} are refused "
                "(a page must not move the robot); allow it with --allow-origin if you mean it\n",
            )
        if self.token is None:
            return None
        header = request.headers.get("Authorization", "")
        query = parse_qs(urlsplit(request.path).query).get("token", [""])[0]
        if header == f"Bearer {self.token}" or query == self.token:
            return None
        return connection.respond(HTTPStatus.UNAUTHORIZED, "rosbridge simulator: missing or wrong token\n")

    def _fanout(self, topic: str, msg: Message) -> None:
        for session in list(self.sessions):
            subscription = session.subscriptions.get(topic)
            if subscription is not None:
                subscription.offer(msg)

    async def _handle(self, connection: ServerConnection) -> None:
        session = ClientSession(self.graph, connection)
        self.sessions.add(session)
        try:
            await session.run()
        finally:
            self.sessions.discard(session)
            session.close()
