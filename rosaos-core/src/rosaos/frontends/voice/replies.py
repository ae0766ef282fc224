"""Speaking back: the kernel's replies to what the voice front end sent, said through the robot.

Processes do not speak for themselves; the kernel's replies go to the updates stream. The voice
front end follows that stream (polling ``GET /updates``, like ``rosaos chat``), keeps the replies
that belong to the commands it sent (the command's event, the processes it launched, their
callbacks: :class:`~rosaos.frontends.chat.Conversation` tells), and says them with the robot's
``speak`` tool.

A quick task answers twice within a moment ("On it: …", then "Done: …"): a reply is said only once
no newer one has come for ``quiet_seconds``, so the user hears the outcome, not both. A long task
still gets its acknowledgement, and later its result.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from rosaos.frontends.chat import Conversation
from rosaos.frontends.voice.robot import RobotLink
from rosaos.kernel.api.kernel_client import KernelClient, KernelUnavailable

POLL_SECONDS = 0.1
QUIET_SECONDS = 0.8
BACKLOG = 500
"""Recent updates kept so a command's first updates are not missed: the poller may read them
before ``POST /stt`` has returned the event id."""
FORGET_SECONDS = 600.0
"""A conversation still open this long after its command is dropped (a stuck process)."""


@dataclass
class _Followed:
    conversation: Conversation
    began: float
    pending: str | None = None
    pending_since: float = 0.0
    spoken: list[str] = field(default_factory=list)


class ReplyFollower:
    """Follows the updates stream and has the robot say the replies to the commands it was told of."""

    def __init__(
        self,
        client: KernelClient,
        robot: RobotLink,
        on_reply: Callable[[int, str, bool], None],
        quiet_seconds: float = QUIET_SECONDS,
    ) -> None:
        self.client = client
        self.robot = robot
        self.on_reply = on_reply
        """Told of each reply as it is said: (event id, text, whether the robot spoke it)."""
        self.quiet_seconds = quiet_seconds
        self._followed: dict[int, _Followed] = {}
        self._backlog: deque[dict[str, Any]] = deque(maxlen=BACKLOG)
        self._cursor: int | None = None

    async def start(self) -> None:
        """Note where the stream is now: replies to commands sent from here on are followed."""
        self._cursor = await self.client.last_update_id()

    def follow(self, event_id: int) -> None:
        """Follow the replies to the command that became event ``event_id``."""
        followed = _Followed(Conversation(event_id), time.monotonic())
        for update in self._backlog:
            self._absorb(followed, update, followed.began)
        self._followed[event_id] = followed

    @property
    def following(self) -> int:
        """How many commands still wait for their replies."""
        return len(self._followed)

    async def run(self) -> None:
        """Poll the stream and speak, until cancelled. A kernel that goes away is waited for."""
        while True:
            # The command hand-off reports an unreachable kernel; here, just try again.
            with contextlib.suppress(KernelUnavailable):
                await self.poll()
            await asyncio.sleep(POLL_SECONDS)

    async def poll(self) -> None:
        """Read new updates once; say the replies that are due; drop what is settled."""
        if self._cursor is None:
            await self.start()
        assert self._cursor is not None
        # Check first, read second (as rosaos chat does): an event's replies commit with its
        # "handled" mark, so updates read after seeing it handled hold all of them.
        was_settled = {
            event_id: (await self._settled(f.conversation), len(f.conversation.processes))
            for event_id, f in self._followed.items()
        }
        updates, self._cursor = await self.client.updates_after(self._cursor)
        now = time.monotonic()
        for update in updates:
            self._backlog.append(update)
            for followed in self._followed.values():
                self._absorb(followed, update, now)
        for event_id, followed in list(self._followed.items()):
            settled_then, known = was_settled.get(event_id, (False, 0))
            settled = settled_then and len(followed.conversation.processes) == known
            quiet = now - followed.pending_since >= self.quiet_seconds
            if followed.pending is not None and (settled or quiet):
                await self._say(event_id, followed)
            if (settled and followed.pending is None) or now - followed.began > FORGET_SECONDS:
                del self._followed[event_id]

    async def settle(self, timeout: float) -> bool:
        """Wait until every followed command is settled and its last reply said (``--wav``)."""
        deadline = time.monotonic() + timeout
        while self._followed:
            if time.monotonic() > deadline:
                return False
            await self.poll()
            if self._followed:
                await asyncio.sleep(POLL_SECONDS)
        return True

    def _absorb(self, followed: _Followed, update: dict[str, Any], now: float) -> None:
        if followed.conversation.absorb(update) and update["kind"] == "kernel_reply":
            followed.pending, followed.pending_since = update["text"], now

    async def _say(self, event_id: int, followed: _Followed) -> None:
        text, followed.pending = followed.pending or "", None
        followed.spoken.append(text)
        self.on_reply(event_id, text, await self.robot.say(text))

    async def _settled(self, conversation: Conversation) -> bool:
        """The command, every process it launched and every callback are handled by the kernel."""
        if not (await self.client.event(conversation.event_id)).get("handled"):
            return False
        if any(not info.get("status") for info in conversation.processes.values()):
            return False
        for callback_event in conversation.callback_events:
            if not (await self.client.event(callback_event)).get("handled"):
                return False
        return True
