"""The ``playback_ended`` notice: the music stopped by itself, with nothing left to play.

A pause someone asked for is not an end: only music that ran out is. Both backends post the
notice through :class:`PlaybackEndNotifier`, so the notice reads the same whichever one runs:

- the simulator, when its optional clock (``sim.track_seconds``) reaches the end of the last track;
- the real backend, from a watcher that reads ``GET /me/player`` every ``watch_seconds``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Awaitable, Callable

from pydantic import BaseModel, Field

from rosaos.drivers import NoticeSpec
from rosaos_spotify.backend import PlayerState

log = logging.getLogger(__name__)

END_PROGRESS_MS = 1500
"""A stopped player this close to the start of its track ran out; a paused one kept its place."""


class PlaybackEnded(BaseModel):
    """The track that played last."""

    track: str | None = Field(default=None, max_length=300)
    artist: str | None = Field(default=None, max_length=300)


NOTICES = {
    "playback_ended": NoticeSpec(
        description="The music stopped by itself: the last track of the album, playlist or queue ended",
        importance="info",
        data=PlaybackEnded,
        example={"track": "Clair de Lune", "artist": "Claude Debussy"},
    )
}

Notify = Callable[..., object]
"""``DeviceContext.notify``: the plugin hands it to the backend after building it."""


class PlaybackEndNotifier:
    """Posts ``playback_ended`` for one instance; silent until the plugin gives it ``notify``."""

    def __init__(self, instance: str) -> None:
        self.instance = instance
        self.notify: Notify | None = None

    def ended(self, track: str | None, artist: str | None) -> None:
        """The music ran out after ``track`` by ``artist``."""
        if self.notify is None:
            return
        what = f"{track} by {artist}" if track and artist else track or "the music"
        self.notify(
            "playback_ended",
            {"track": track, "artist": artist},
            message=f"playback ended after {what}",
        )


def ran_out(before: PlayerState | None, after: PlayerState, progress_ms: int | None) -> bool:
    """Whether a player read as ``after`` stopped by itself since it was read as ``before``.

    It was playing, it is not now, and it is back at the start of a track (or has none loaded):
    Spotify rewinds the last track when a context ends, while a pause keeps the position.
    """
    if before is None or not before.is_playing or after.is_playing:
        return False
    return after.track is None or progress_ms is None or progress_ms < END_PROGRESS_MS


class PeriodicTask:
    """Runs ``step`` every ``period`` seconds in the background until :meth:`stop`.

    A failing step is logged and the next one still runs: a watcher must outlive a bad read.
    """

    def __init__(self, name: str, period: float, step: Callable[[float], Awaitable[None]]) -> None:
        self.name = name
        self.period = period
        self.step = step
        self._task: asyncio.Task[None] | None = None

    def start(self) -> None:
        """Start running (once)."""
        if self._task is None:
            self._task = asyncio.create_task(self._run(), name=self.name)

    async def stop(self) -> None:
        """Stop and wait for the task to finish."""
        task, self._task = self._task, None
        if task is not None:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task

    async def _run(self) -> None:
        last = time.monotonic()
        while True:
            await asyncio.sleep(self.period)
            now = time.monotonic()
            try:
                await self.step(now - last)
            except Exception:
                log.exception("%s failed", self.name)
            last = now
