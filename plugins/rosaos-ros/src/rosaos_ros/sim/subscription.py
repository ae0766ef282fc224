"""A rosbridge client's subscription to one topic: throttling and queueing, as rosbridge does them."""

from __future__ import annotations

import asyncio
import math
import time
from collections import deque
from typing import TYPE_CHECKING

from rosaos_ros.sim.graph import Message

if TYPE_CHECKING:
    from rosaos_ros.sim.session import ClientSession


class ClientSubscription:
    """One client's subscription to one topic, possibly under several ids (as rosbridge merges them).

    The effective throttle is the smallest asked for, the queue the longest. With a queue, the
    newest ``queue_length`` messages wait while the throttle or a slow socket holds them back;
    without one, a message inside the throttle window is dropped.
    """

    def __init__(self, session: ClientSession, topic: str) -> None:
        self.session = session
        self.topic = topic
        self.ids: dict[str, tuple[int, int]] = {}
        self.last_sent = -math.inf
        self.pending: deque[Message] = deque(maxlen=1)
        self._wake = asyncio.Event()
        self._drain: asyncio.Task[None] | None = None

    @property
    def throttle(self) -> float:
        return min(throttle for throttle, _ in self.ids.values()) / 1000 if self.ids else 0.0

    @property
    def queue_length(self) -> int:
        return max(queue for _, queue in self.ids.values()) if self.ids else 0

    def add(self, sub_id: str, throttle_ms: int, queue_length: int) -> None:
        self.ids[sub_id] = (max(0, throttle_ms), max(0, queue_length))
        self.pending = deque(self.pending, maxlen=max(1, self.queue_length))
        if self.queue_length and self._drain is None:
            self._drain = asyncio.get_running_loop().create_task(self._drain_queue())

    def offer(self, msg: Message) -> None:
        """A message was published on the topic."""
        if self.queue_length:
            self.pending.append(msg)
            self._wake.set()
            return
        now = time.monotonic()
        if self.throttle and now - self.last_sent < self.throttle:
            return
        self.last_sent = now
        self.session.send({"op": "publish", "topic": self.topic, "msg": msg})

    def cancel(self) -> None:
        if self._drain is not None:
            self._drain.cancel()

    async def _drain_queue(self) -> None:
        while True:
            await self._wake.wait()
            self._wake.clear()
            while self.pending:
                delay = self.last_sent + self.throttle - time.monotonic()
                if delay > 0:
                    await asyncio.sleep(delay)
                await self.session.caught_up()  # meanwhile only the newest messages are kept
                if not self.pending:
                    break
                self.last_sent = time.monotonic()
                self.session.send({"op": "publish", "topic": self.topic, "msg": self.pending.popleft()})
