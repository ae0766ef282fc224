"""What both Spotify backends do, and the shapes they answer in.

- ``real`` (:mod:`rosaos_spotify.web_api`): the user's Spotify account through the Web API
  (spotipy), playing on one of their Spotify Connect devices (phone, computer, speaker).
- ``sim`` (:mod:`rosaos_spotify.simulator`): an in-process player over a small catalog.

The server (:mod:`rosaos_spotify.server`) is written against :class:`SpotifyBackend` only, so
both backends offer exactly the same tools. Every action returns a :class:`PlayerReport`: one
readable sentence and the player state afterwards, with the keys of ``get_state``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Annotated, Literal

from pydantic import BaseModel, Field

from rosaos.drivers import DeviceBackend
from rosaos_spotify.catalog import SearchKind

Repeat = Literal["off", "track", "context"]
"""Spotify's repeat modes: ``track`` repeats the song, ``context`` the album/playlist/artist."""


class PlayerState(BaseModel):
    """What ``get_state`` returns: exactly the ``spotify`` keys of the task benchmark."""

    is_playing: bool = Field(description="Whether music is playing now (false when paused or stopped).")
    volume: Annotated[int, Field(ge=0, le=100, description="Volume of the playing device, in percent.")]
    track: str | None = Field(description="Title of the current track; null when nothing is loaded.")
    artist: str | None = Field(description="Artist(s) of the current track; null when nothing is loaded.")
    shuffle: bool = Field(description="Whether shuffle is on.")
    repeat: Repeat = Field(description="off, track (repeat the song) or context (repeat the album/playlist).")


class PlayerReport(BaseModel):
    """What every action tool returns: what happened, in a sentence, and the state after it."""

    message: str = Field(description='What happened, e.g. "Playing Clair de Lune by Claude Debussy."')
    state: PlayerState


class SearchHit(BaseModel):
    """One search result: a track, an artist, an album or a genre."""

    kind: Literal["track", "artist", "album", "genre"]
    name: str = Field(description="Track title, artist name, album title or genre.")
    artist: str | None = Field(default=None, description="For tracks and albums: by whom.")
    album: str | None = Field(default=None, description="For tracks: the album it is on.")


class SearchResults(BaseModel):
    """What ``search`` returns: the best matches first. Searching never changes playback."""

    message: str
    hits: list[SearchHit]


class SpotifyBackend(DeviceBackend, ABC):
    """The operations behind the tools. Failures raise :class:`rosaos.drivers.DeviceError`
    whose message says what to do; a failed action leaves the player as it was."""

    @abstractmethod
    async def state(self) -> PlayerState:
        """The player as it is now."""

    @abstractmethod
    async def play(self, query: str, kind: SearchKind = "any") -> PlayerReport:
        """Find ``query`` (a track, artist, album or genre) and play it, replacing what plays."""

    @abstractmethod
    async def pause(self) -> PlayerReport:
        """Pause playback; nothing to do when already paused or nothing is playing."""

    @abstractmethod
    async def resume(self) -> PlayerReport:
        """Resume the current track where it was paused."""

    @abstractmethod
    async def next_track(self) -> PlayerReport:
        """Skip to the next track: the queue first, then the current album/artist/genre/playlist."""

    @abstractmethod
    async def previous_track(self) -> PlayerReport:
        """Go back to the previous track of the current context."""

    @abstractmethod
    async def set_volume(self, volume: int) -> PlayerReport:
        """Set the volume to ``volume`` percent (0-100)."""

    async def change_volume(self, delta: int) -> PlayerReport:
        """Raise or lower the volume by ``delta`` percentage points, kept within 0-100."""
        current = await self.state()
        return await self.set_volume(min(100, max(0, current.volume + delta)))

    @abstractmethod
    async def set_shuffle(self, shuffle: bool) -> PlayerReport:
        """Turn shuffle on or off for the current context."""

    @abstractmethod
    async def set_repeat(self, repeat: Repeat) -> PlayerReport:
        """Set the repeat mode: off, track or context."""

    @abstractmethod
    async def queue(self, query: str) -> PlayerReport:
        """Find one track for ``query`` and add it to the queue: it plays after the current one."""

    @abstractmethod
    async def search(self, query: str, kind: SearchKind = "any", limit: int = 5) -> SearchResults:
        """Find tracks, artists, albums or genres without playing anything."""


def volume_message(old: int, new: int) -> str:
    """How the volume changed ("Volume 40% → 70%."), for the volume tools' reports."""
    if old == new:
        return f"Volume stays at {new}%."
    return f"Volume {old}% → {new}%."
