"""The ``real`` backend: the user's Spotify account through the Web API, with spotipy.

Spotify plays *on* a Spotify Connect device (the app on a phone or computer, a smart speaker);
this backend remote-controls it. The device is the ``device`` setting (by name or id) or, if
unset, whichever is active; with none active, playback starts on the first idle one online.

spotipy is synchronous (requests), so every call runs in a thread, one at a time. The player's
state is eventually consistent: right after a command ``GET /me/player`` may still show the old
track, so actions poll briefly for the change and report what they did on top of what they read.
"""

from __future__ import annotations

import asyncio
import itertools
from collections.abc import Callable
from pathlib import Path
from typing import Any

import requests
import spotipy
from urllib3.util.retry import Retry

from rosaos.drivers import DeviceError
from rosaos_spotify.auth import NotLoggedIn, TokenCache, auth_manager, token_path
from rosaos_spotify.backend import (
    PlayerReport,
    PlayerState,
    Repeat,
    SearchResults,
    SpotifyBackend,
    volume_message,
)
from rosaos_spotify.catalog import KNOWN_GENRES, SearchKind, clean_query, normalize
from rosaos_spotify.ending import PeriodicTask, PlaybackEndNotifier, ran_out
from rosaos_spotify.errors import (
    NO_ACTIVE_DEVICE,
    RESTRICTION_VIOLATED,
    SpotifyError,
    login_hint,
    spotify_error,
)
from rosaos_spotify.settings import SpotifySettings
from rosaos_spotify.web_answers import (
    PlayTarget,
    artists_of,
    describe_track,
    not_found,
    play_target,
    search_hit,
    section,
    state_of,
)

RETRY_STATUSES = (500, 502, 503, 504)
"""Retried, twice. Not 429: its Retry-After can be hours; the tool says so instead of hanging."""
SETTLE_ATTEMPTS = 4
SETTLE_DELAY = 0.3
"""Seconds between reads while waiting for Spotify to show a command's effect."""
_GENRES = {normalize(genre) for genre in KNOWN_GENRES}


def build_web_backend(instance: str, settings: SpotifySettings, data_dir: Path) -> WebApiBackend:
    """A backend for ``instance`` using the login saved by ``rosaos devices login``."""
    if not settings.client_id:
        raise DeviceError(f"[devices.{instance}] needs client_id for the real backend (see the README)")
    cache = TokenCache(token_path(data_dir, instance))
    client = spotipy.Spotify(
        auth_manager=auth_manager(settings.client_id, settings.redirect_uri, cache, settings.timeout),
        requests_session=api_session(),
        requests_timeout=settings.timeout,
    )
    return WebApiBackend(
        instance,
        client,
        cache,
        device=settings.device,
        market=settings.market,
        watch_seconds=settings.watch_seconds,
    )


def api_session() -> requests.Session:
    """An HTTP session that retries what is safe to retry, and never sleeps on Retry-After.

    spotipy's own session honours Retry-After (a tool call would hang for as long as Spotify
    says) and retries POSTs (``next_track`` after a 502 could skip twice). Here only reads and
    Spotify's idempotent PUTs (play, pause, volume...) are retried, and only on server errors.
    """
    retry = Retry(
        total=2,
        read=False,
        status_forcelist=RETRY_STATUSES,
        allowed_methods=frozenset({"GET", "PUT"}),
        backoff_factor=0.3,
        respect_retry_after_header=False,
        raise_on_status=False,  # the last 5xx answer reaches spotipy, which reports its status
    )
    session = requests.Session()
    session.mount("https://", requests.adapters.HTTPAdapter(max_retries=retry))
    return session


class WebApiBackend(SpotifyBackend):
    """Spotify playback of one account, remote-controlled through the Web API."""

    def __init__(
        self,
        instance: str,
        client: Any,
        cache: TokenCache,
        *,
        device: str | None = None,
        market: str | None = None,
        settle_delay: float = SETTLE_DELAY,
        watch_seconds: float = 0.0,
    ) -> None:
        self.instance = instance
        self.client = client
        """A ``spotipy.Spotify`` (untyped, hence ``Any``)."""
        self.cache = cache
        self.device = device
        self.market = market or "from_token"
        self.settle_delay = settle_delay
        self._lock = asyncio.Lock()
        self.ending = PlaybackEndNotifier(instance)
        self._watcher = (
            PeriodicTask(f"{instance} player watcher", watch_seconds, self.watch)
            if watch_seconds > 0
            else None
        )
        self._seen: PlayerState | None = None
        """The player as the watcher (or our own pause) last saw it."""

    async def start(self) -> None:
        """Check that a login is saved, and start watching for the end of the music.

        The network is first used by the first tool call or the watcher's first read.
        """
        if not await asyncio.to_thread(self.cache.has_login):
            raise DeviceError(f"{self.instance} is not logged in to Spotify: {login_hint(self.instance)}")
        if self._watcher is not None:
            self._watcher.start()

    async def close(self) -> None:
        """Stop the watcher."""
        if self._watcher is not None:
            await self._watcher.stop()

    async def watch(self, _elapsed: float = 0.0) -> None:
        """Read the player once; post ``playback_ended`` when it stopped by itself since the last read."""
        playback = await self._api(self.client.current_playback, market=self.market)
        state = state_of(playback) if playback else None
        now = state or PlayerState(
            is_playing=False, volume=0, track=None, artist=None, shuffle=False, repeat="off"
        )
        before, self._seen = self._seen, now
        if ran_out(before, now, (playback or {}).get("progress_ms")) and before is not None:
            self.ending.ended(before.track, before.artist)

    # Calling Spotify

    async def _api(self, method: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        """Call a spotipy method in a thread; failures become :class:`SpotifyError`."""
        async with self._lock:
            try:
                return await asyncio.to_thread(self._call_refreshing, method, args, kwargs)
            except Exception as error:
                raise spotify_error(error, self.instance) from None

    def _call_refreshing(self, method: Callable[..., Any], args: Any, kwargs: Any) -> Any:
        try:
            return method(*args, **kwargs)
        except spotipy.SpotifyException as error:
            if error.http_status != 401:
                raise
        # The access token died before spotipy expected (revoked, clock skew): refresh it once
        # and retry. A refused refresh (invalid_grant) then reads "log in again".
        token = self.cache.get_cached_token() or {}
        if not token.get("refresh_token"):
            raise NotLoggedIn("no refresh token saved", error="not_logged_in")
        self.client.auth_manager.refresh_access_token(token["refresh_token"])
        return method(*args, **kwargs)

    async def _devices(self) -> list[dict[str, Any]]:
        answer = await self._api(self.client.devices)
        return [device for device in (answer or {}).get("devices") or [] if device.get("id")]

    async def _device_id(self) -> str | None:
        """The id of the ``device`` setting's device; None (the active one) when unset."""
        if self.device is None:
            return None
        devices = await self._devices()
        preferred = self._preferred(devices)
        if preferred:
            return str(preferred[0]["id"])
        online = ", ".join(f'"{device.get("name")}"' for device in devices) or "none"
        raise DeviceError(
            f'no Spotify device called "{self.device}" is online (online now: {online}): open Spotify '
            f"on it, or change device in [devices.{self.instance}]"
        )

    def _preferred(self, devices: list[dict[str, Any]]) -> list[dict[str, Any]]:
        """The devices the ``device`` setting names, by id or by name in any case."""
        wanted = (self.device or "").casefold()
        return [d for d in devices if wanted in (str(d["id"]).casefold(), str(d.get("name", "")).casefold())]

    async def _start_playback(self, **body: Any) -> None:
        device_id = await self._device_id()
        try:
            await self._api(self.client.start_playback, device_id=device_id, **body)
        except SpotifyError as error:
            if error.reason != NO_ACTIVE_DEVICE or device_id is not None:
                raise
            # Nothing is active, but a Spotify app may be open and idle: start it there.
            idle = [device for device in await self._devices() if not device.get("is_restricted")]
            if not idle:
                raise
            await self._api(self.client.start_playback, device_id=idle[0]["id"], **body)

    # State

    async def state(self) -> PlayerState:
        """Read ``GET /me/player``; with nothing active, the volume of the device we would use."""
        playback = await self._api(self.client.current_playback, market=self.market)
        if playback:
            return state_of(playback)
        devices = await self._devices()
        chosen = self._preferred(devices) or devices
        volume = chosen[0].get("volume_percent") if chosen else None
        return PlayerState(
            is_playing=False, volume=volume or 0, track=None, artist=None, shuffle=False, repeat="off"
        )

    async def _settled(self, done: Callable[[PlayerState], bool]) -> PlayerState:
        state = await self.state()
        for _ in range(SETTLE_ATTEMPTS - 1):
            if done(state):
                break
            await asyncio.sleep(self.settle_delay)
            state = await self.state()
        return state

    # Actions

    async def play(self, query: str, kind: SearchKind = "any") -> PlayerReport:
        """Search Spotify for ``query`` and play the best match in its context."""
        cleaned, hinted = clean_query(query)
        if not cleaned:
            return await self.resume()
        target = await self._find(query, cleaned, kind if kind != "any" else hinted)
        await self._start_playback(context_uri=target.context_uri, uris=target.uris, offset=target.offset)
        state = await self._settled(lambda s: s.is_playing and target.track in (None, s.track))
        known = {"track": target.track, "artist": target.artist} if target.track else {}
        return PlayerReport(
            message=f"Playing {target.description}.",
            state=state.model_copy(update={"is_playing": True, **known}),
        )

    async def pause(self) -> PlayerReport:
        """Pause; fine when already paused or when no device is active."""
        message = "Paused."
        try:
            await self._api(self.client.pause_playback, device_id=await self._device_id())
        except SpotifyError as error:
            if error.reason not in (NO_ACTIVE_DEVICE, RESTRICTION_VIOLATED):
                raise
            message = "Nothing is playing." if error.reason == NO_ACTIVE_DEVICE else "Already paused."
        state = await self._settled(lambda s: not s.is_playing)
        self._seen = state  # a pause someone asked for is not the music ending
        return PlayerReport(message=message, state=state.model_copy(update={"is_playing": False}))

    async def resume(self) -> PlayerReport:
        """Resume where Spotify left off (on the active device, or the first idle one)."""
        message = "Resumed."
        try:
            await self._start_playback()
        except SpotifyError as error:
            if error.reason != RESTRICTION_VIOLATED:
                raise
            message = "Already playing."
        state = await self._settled(lambda s: s.is_playing)
        return PlayerReport(message=message, state=state.model_copy(update={"is_playing": True}))

    async def next_track(self) -> PlayerReport:
        """Skip to the next track (the queue first)."""
        return await self._skip(self.client.next_track)

    async def previous_track(self) -> PlayerReport:
        """Go back to the previous track."""
        return await self._skip(self.client.previous_track)

    async def _skip(self, command: Callable[..., Any]) -> PlayerReport:
        before = await self.state()
        await self._api(command, device_id=await self._device_id())
        state = await self._settled(lambda s: s.track != before.track)
        now = f"{state.track} by {state.artist}" if state.track else "the next track"
        return PlayerReport(message=f"Playing {now}.", state=state.model_copy(update={"is_playing": True}))

    async def set_volume(self, volume: int) -> PlayerReport:
        """Set the volume of the playing device."""
        return await self._apply_volume((await self.state()).volume, volume)

    async def change_volume(self, delta: int) -> PlayerReport:
        """Raise or lower the volume by ``delta`` points, kept within 0-100."""
        old = (await self.state()).volume
        return await self._apply_volume(old, min(100, max(0, old + delta)))

    async def _apply_volume(self, old: int, new: int) -> PlayerReport:
        await self._api(self.client.volume, new, device_id=await self._device_id())
        state = await self.state()
        return PlayerReport(message=volume_message(old, new), state=state.model_copy(update={"volume": new}))

    async def set_shuffle(self, shuffle: bool) -> PlayerReport:
        """Turn shuffle on or off."""
        await self._api(self.client.shuffle, shuffle, device_id=await self._device_id())
        state = (await self.state()).model_copy(update={"shuffle": shuffle})
        return PlayerReport(message=f"Shuffle {'on' if shuffle else 'off'}.", state=state)

    async def set_repeat(self, repeat: Repeat) -> PlayerReport:
        """Set the repeat mode."""
        await self._api(self.client.repeat, repeat, device_id=await self._device_id())
        state = (await self.state()).model_copy(update={"repeat": repeat})
        return PlayerReport(message=f"Repeat {repeat}.", state=state)

    async def queue(self, query: str) -> PlayerReport:
        """Add the best matching track to the queue."""
        cleaned, hinted = clean_query(query)
        if not cleaned:
            raise DeviceError("say what to queue: a track title, an artist, an album or a genre")
        genre = hinted == "genre" or normalize(cleaned) in _GENRES
        tracks = await self._items(f'genre:"{cleaned}"' if genre else cleaned, "track", 1)
        if not tracks:
            raise not_found(query)
        await self._api(self.client.add_to_queue, tracks[0]["uri"], device_id=await self._device_id())
        return PlayerReport(message=f"Queued {describe_track(tracks[0])}.", state=await self.state())

    async def search(self, query: str, kind: SearchKind = "any", limit: int = 5) -> SearchResults:
        """Search Spotify's catalog without playing anything."""
        cleaned, hinted = clean_query(query)
        kind = kind if kind != "any" else hinted
        if not cleaned:
            raise DeviceError("say what to search for: a track title, an artist, an album or a genre")
        if kind == "genre":
            found = {"tracks": {"items": await self._items(f'genre:"{cleaned}"', "track", limit)}}
        else:
            types = "track,artist,album" if kind == "any" else kind
            found = await self._api(
                self.client.search, q=cleaned, type=types, limit=limit, market=self.market
            )
        # Round-robin over the kinds, so a short list still shows the top artist and album.
        sections = [
            [search_hit(name, item) for item in section(found, name)] for name in ("track", "artist", "album")
        ]
        hits = [hit for row in itertools.zip_longest(*sections) for hit in row if hit is not None]
        if not hits:
            raise not_found(query)
        return SearchResults(message=f'{len(hits[:limit])} result(s) for "{query}".', hits=hits[:limit])

    # Finding what to play

    async def _items(self, q: str, kind: str, limit: int) -> list[dict[str, Any]]:
        found = await self._api(self.client.search, q=q, type=kind, limit=limit, market=self.market)
        return section(found, kind)

    async def _find(self, query: str, cleaned: str, kind: SearchKind) -> PlayTarget:
        wanted = normalize(cleaned)
        if kind == "genre" or (kind == "any" and wanted in _GENRES):
            tracks = await self._items(f'genre:"{cleaned}"', "track", 20)
            if tracks:
                first = tracks[0]
                return PlayTarget(
                    f"some {cleaned}: {describe_track(first)}",
                    uris=[track["uri"] for track in tracks],
                    track=first["name"],
                    artist=artists_of(first),
                )
            if kind == "genre":
                raise not_found(query)
        types = "track,artist,album" if kind in ("any", "genre") else kind
        found = await self._api(self.client.search, q=cleaned, type=types, limit=5, market=self.market)
        tracks, artists, albums = (section(found, name) for name in ("track", "artist", "album"))

        def exact(items: list[dict[str, Any]]) -> dict[str, Any] | None:
            return next((item for item in items if normalize(item.get("name", "")) == wanted), None)

        # An exact name wins ("Queen" the band, "Thriller" the song); else Spotify's top result.
        for kind_, item in (
            ("artist", exact(artists)),
            ("track", exact(tracks)),
            ("album", exact(albums)),
            ("track", tracks[0] if tracks else None),
            ("artist", artists[0] if artists else None),
            ("album", albums[0] if albums else None),
        ):
            if item is not None:
                return play_target(kind_, item)
        raise not_found(query)
