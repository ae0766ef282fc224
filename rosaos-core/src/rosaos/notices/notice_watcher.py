"""Device notices, kernel side: fetch them from every device, filter, and enqueue the ones that pass.

One task per host long-polls ``POST /host/notices`` for all the devices it serves
(:mod:`rosaos.devices.host_notices`; a device alone on its host: its ``GET /notices``,
:mod:`rosaos.notices.notice_board`) with the devices' own token, so a device host never holds the
kernel's token and a remote device works the same as a local one. Each notice that passes :class:`NoticeFilter` becomes a ``device_notice``
event with an idempotency key made from the board and sequence number, so a notice fetched twice
(a retry after a lost answer) is enqueued once.

The filter is where "rate-limited and deduplicated" lives:

- the same notice (device, name and data) again within ``repeat_window`` seconds is dropped;
- the same name from the same device more often than every ``min_interval`` seconds is dropped;
- a device is allowed at most ``per_minute`` notices a minute.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import time
from collections import deque
from collections.abc import Awaitable, Callable, Mapping

import httpx
from pydantic import ValidationError

from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.devices.host_notices import HOST_NOTICES_PATH, BoardCursor, HostNoticeAnswer, HostNoticeQuery
from rosaos.events.types import DeviceNotice, DeviceNoticeEvent
from rosaos.notices.notice_board import MAX_WAIT, Notice, NoticeBatch
from rosaos.tls import shared_context

log = logging.getLogger(__name__)

POLL_WAIT = 15.0
"""Seconds one long poll waits for a notice before asking again."""
RETRY_DELAY = 2.0
"""Seconds before asking a device again after it did not answer (restarting, unreachable)."""


class NoticeFilter:
    """Decides which notices reach the kernel's queue; see the module docstring for the rules."""

    def __init__(
        self,
        repeat_window: float = 300.0,
        min_interval: float = 10.0,
        per_minute: int = 10,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.repeat_window = repeat_window
        self.min_interval = min_interval
        self.per_minute = per_minute
        self._clock = clock
        self._seen: dict[str, float] = {}
        self._last_name: dict[tuple[str, str], float] = {}
        self._recent: dict[str, deque[float]] = {}
        self.dropped = 0
        """How many notices were dropped (for tests and ``rosaos log``'s curious reader)."""

    def admit(self, notice: Notice) -> str | None:
        """None when ``notice`` may be enqueued (and remember it); else why it is dropped."""
        now = self._clock()
        key = f"{notice.device}\0{notice.name}\0{json.dumps(notice.data, sort_keys=True)}"
        reason = None
        if now - self._seen.get(key, float("-inf")) < self.repeat_window:
            reason = "a repeat"
        elif now - self._last_name.get((notice.device, notice.name), float("-inf")) < self.min_interval:
            reason = f"more than one {notice.name} within {self.min_interval:g} s"
        else:
            recent = self._recent.setdefault(notice.device, deque())
            while recent and now - recent[0] >= 60.0:
                recent.popleft()
            if len(recent) >= self.per_minute:
                reason = f"over {self.per_minute} notices a minute from {notice.device}"
            else:
                recent.append(now)
        if reason is not None:
            self.dropped += 1
            return reason
        self._seen[key] = now
        self._last_name[(notice.device, notice.name)] = now
        if len(self._seen) > 1000:  # forget the oldest; a notice this old may come again
            for old in sorted(self._seen, key=self._seen.__getitem__)[:500]:
                del self._seen[old]
        return None


def notice_event(notice: Notice, board: str) -> DeviceNoticeEvent:
    """The ``device_notice`` event for a notice fetched from ``board``."""
    return DeviceNoticeEvent(
        kind="device_notice",
        source=notice.device,
        idempotency_key=f"notice:{notice.device}:{board}:{notice.seq}",
        payload=DeviceNotice(
            device=notice.device,
            message=notice.message,
            data=notice.data,
            name=notice.name,
            driver=notice.driver,
            importance=notice.importance,
        ),
    )


def _base(mcp_url: str) -> str:
    base = mcp_url.rstrip("/")
    return base[: -len("/mcp")] if base.endswith("/mcp") else base


def notices_url(mcp_url: str) -> str:
    """A device's ``/notices`` URL, from its MCP URL (``http://host:port/mcp``)."""
    return _base(mcp_url) + "/notices"


def host_notices_url(mcp_url: str) -> str:
    """The ``/host/notices`` URL of the server at ``mcp_url`` (it reads its whole host's boards)."""
    return _base(mcp_url) + HOST_NOTICES_PATH


def host_groups(endpoints: Mapping[str, DeviceEndpoint]) -> list[tuple[str, ...]]:
    """The served devices grouped by host and token, each group sorted: one long poll each.

    A device without a host (its own process, a remote one) or not served now is a group of its
    own (its poll waits for it to be served)."""
    groups: dict[tuple[str, str], list[str]] = {}
    alone: list[tuple[str, ...]] = []
    for name, endpoint in endpoints.items():
        if endpoint.host and endpoint.url is not None:
            groups.setdefault((endpoint.host, endpoint.token), []).append(name)
        else:
            alone.append((name,))
    return sorted([tuple(sorted(names)) for names in groups.values()] + alone)


class NoticeWatcher:
    """Fetches every device's notices and hands those the filter admits to ``enqueue``.

    Devices that one host process serves (:attr:`DeviceEndpoint.host`, with the same token) are
    read together, with one long poll on ``POST /host/notices`` (:mod:`rosaos.devices.host_notices`):
    so idle, the kernel holds one request per host, not one per device. A device alone on its host,
    or on a server without that route, is polled on its own ``GET /notices``.
    """

    def __init__(
        self,
        endpoints: Callable[[], Mapping[str, DeviceEndpoint]],
        enqueue: Callable[[DeviceNoticeEvent], Awaitable[object]],
        notice_filter: NoticeFilter | None = None,
        wait: float = POLL_WAIT,
    ) -> None:
        self._endpoints = endpoints
        self._enqueue = enqueue
        self.filter = notice_filter or NoticeFilter()
        self.wait = min(wait, MAX_WAIT)
        self._tasks: dict[tuple[str, ...], asyncio.Task[None]] = {}
        self._cursors: dict[str, tuple[str | None, int]] = {}
        """Per device: the board life and sequence number read so far (kept when the groups change)."""

    def pollers(self) -> list[tuple[str, ...]]:
        """The devices each running long poll reads (one tuple per poll; for tests and benchmarks)."""
        return [names for names, task in self._tasks.items() if not task.done()]

    async def run(self) -> None:
        """Watch every device until cancelled (devices added to the world later are picked up)."""
        try:
            # One long poll per host or lone device, all open at once: httpx's default pool
            # (100 connections, 20 kept alive) would make the 101st wait.
            limits = httpx.Limits(max_connections=None, max_keepalive_connections=None)
            async with httpx.AsyncClient(
                timeout=self.wait + 10, limits=limits, verify=shared_context()
            ) as client:
                seen: Mapping[str, DeviceEndpoint] | None = None
                groups: list[tuple[str, ...]] = []
                while True:
                    endpoints = self._endpoints()
                    if endpoints is not seen:  # the kernel's directory is rebuilt only on a change
                        seen, groups = endpoints, host_groups(endpoints)
                        for names in [names for names in self._tasks if names not in groups]:
                            self._tasks.pop(names).cancel()  # its members moved: regrouped below
                    for names in groups:
                        if names not in self._tasks or self._tasks[names].done():
                            self._tasks[names] = asyncio.create_task(self._poll(client, names))
                    await asyncio.sleep(5.0)
        finally:
            for task in self._tasks.values():
                task.cancel()
            with contextlib.suppress(Exception):
                await asyncio.gather(*self._tasks.values(), return_exceptions=True)

    async def _poll(self, client: httpx.AsyncClient, names: tuple[str, ...]) -> None:
        if len(names) == 1:
            await self._watch(client, names[0])
            return
        alone: list[asyncio.Task[None]] = []  # members the host did not know, each polled on its own
        members = list(names)
        try:
            while members:
                endpoints = self._endpoints()
                served = [name for name in members if (e := endpoints.get(name)) is not None and e.url]
                if not served:
                    await asyncio.sleep(RETRY_DELAY)
                    continue
                try:
                    answer = await self._fetch_host(client, endpoints[served[0]], served)
                except (httpx.HTTPError, ValidationError, ValueError) as error:
                    log.debug("notices of host %s: %s", endpoints[served[0]].host, error)
                    await asyncio.sleep(RETRY_DELAY)
                    continue
                if answer is None:  # a server without /host/notices (an older rosaOS): one by one
                    answer = HostNoticeAnswer(unknown=members)
                for name, batch in answer.batches.items():
                    if name in members:
                        await self._take(name, batch)
                for name in answer.unknown:
                    if name in members:
                        members.remove(name)
                        alone.append(asyncio.create_task(self._watch(client, name)))
            await asyncio.gather(*alone)
        finally:
            for task in alone:
                task.cancel()

    async def _take(self, name: str, batch: NoticeBatch) -> None:
        for notice in batch.notices:
            await self.offer(notice, batch.board)
        self._cursors[name] = (batch.board, batch.next)

    async def _watch(self, client: httpx.AsyncClient, name: str) -> None:
        while True:
            endpoint = self._endpoints().get(name)
            if endpoint is None or endpoint.url is None:
                await asyncio.sleep(RETRY_DELAY)
                continue
            try:
                batch = await self._fetch(client, endpoint, *self._cursors.get(name, (None, 0)))
            except (httpx.HTTPError, ValidationError, ValueError) as error:
                log.debug("notices of %s: %s", name, error)
                await asyncio.sleep(RETRY_DELAY)
                continue
            if batch is None:  # a device server without /notices (an older rosaOS)
                await asyncio.sleep(60.0)
                continue
            await self._take(name, batch)

    async def _fetch(
        self, client: httpx.AsyncClient, endpoint: DeviceEndpoint, board: str | None, after: int
    ) -> NoticeBatch | None:
        assert endpoint.url is not None
        params: dict[str, str | int | float] = {"after": after, "wait": self.wait}
        if board is not None:
            params["board"] = board
        response = await client.get(
            notices_url(endpoint.url), params=params, headers={"Authorization": f"Bearer {endpoint.token}"}
        )
        if response.status_code == 404:
            return None
        response.raise_for_status()
        return NoticeBatch.model_validate_json(response.content)

    async def _fetch_host(
        self, client: httpx.AsyncClient, anchor: DeviceEndpoint, names: list[str]
    ) -> HostNoticeAnswer | None:
        """One long poll for ``names`` through ``anchor``'s server; None when it has no such route."""
        assert anchor.url is not None
        boards = {}
        for name in names:
            board, after = self._cursors.get(name, (None, 0))
            boards[name] = BoardCursor(after=after, board=board)
        query = HostNoticeQuery(boards=boards, wait=self.wait)
        response = await client.post(
            host_notices_url(anchor.url),
            content=query.model_dump_json(),
            headers={"Authorization": f"Bearer {anchor.token}", "Content-Type": "application/json"},
        )
        if response.status_code in (404, 405):
            return None
        response.raise_for_status()
        return HostNoticeAnswer.model_validate_json(response.content)

    async def offer(self, notice: Notice, board: str) -> bool:
        """Enqueue ``notice`` unless the filter drops it; True when enqueued."""
        reason = self.filter.admit(notice)
        if reason is not None:
            log.info("notice %s from %s dropped: %s", notice.name, notice.device, reason)
            return False
        await self._enqueue(notice_event(notice, board))
        return True
