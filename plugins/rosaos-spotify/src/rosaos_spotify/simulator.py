"""The ``sim`` backend: an in-process Spotify player over a small catalog.

It behaves like the Spotify app in the ways a task can observe through ``get_state``:

- ``play`` finds a track, artist, album or genre (:func:`rosaos_spotify.catalog.find`) and plays
  it in a *context*: a track plays within its album; an artist, album or genre plays all its tracks.
- ``next_track`` takes the queue first, then the context; at the end of the context, ``repeat =
  context`` starts it over, otherwise *autoplay* continues with similar music (same genre first),
  as Spotify does. ``previous_track`` goes back within the context.
- ``shuffle`` plays the context in a random order, seeded by the instance name so a run can be
  repeated. ``repeat = track`` keeps the song going until someone skips.
- Time stands still unless ``track_seconds`` is set: then every track lasts that long, the player
  moves on by itself, and when the last one ends (repeat off, ``autoplay = false``) it stops and
  posts the ``playback_ended`` notice. The default keeps a benchmark's end state stable.

The initial state comes from the instance's ``sim`` table: the ``get_state`` keys plus
``catalog`` (a list of ``{track, artist, album, genre}``; default :data:`DEFAULT_CATALOG`).
"""

from __future__ import annotations

import random
from collections import deque
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from rosaos.drivers import DeviceError
from rosaos_spotify.backend import (
    PlayerReport,
    PlayerState,
    Repeat,
    SearchHit,
    SearchResults,
    SpotifyBackend,
    volume_message,
)
from rosaos_spotify.catalog import (
    DEFAULT_CATALOG,
    CatalogEntry,
    Match,
    SearchKind,
    clean_query,
    describe,
    find,
    normalize,
    suggestions,
)
from rosaos_spotify.ending import PeriodicTask, PlaybackEndNotifier

CLOCK_PERIOD = 0.5
"""Seconds between the simulated clock's ticks (shorter when tracks are shorter)."""


class SimSettings(BaseModel):
    """The ``sim`` table of a ``spotify`` instance: the initial ``get_state`` keys, and the catalog."""

    model_config = ConfigDict(extra="forbid")

    is_playing: bool = False
    volume: Annotated[int, Field(ge=0, le=100)] = 50
    track: str | None = None
    artist: str | None = None
    shuffle: bool = False
    repeat: Repeat = "off"
    catalog: Annotated[list[CatalogEntry], Field(min_length=1)] | None = None
    """Tracks the simulated Spotify knows; the built-in :data:`DEFAULT_CATALOG` when omitted."""
    track_seconds: Annotated[float, Field(gt=0, le=3600)] | None = None
    """How long every track lasts; None (the default): time stands still and tracks never end."""
    autoplay: bool = True
    """After the last track of a context, keep going with similar music (as Spotify does by default)."""

    @classmethod
    def from_sim(cls, instance: str, sim: dict[str, Any]) -> SimSettings:
        """Validate an instance's ``sim`` table, or raise :class:`DeviceError` saying what is wrong."""
        where = f"devices.{instance}.sim"
        unknown = sorted(set(sim) - set(cls.model_fields))
        if unknown:
            raise DeviceError(
                f"{where}: unknown key(s) {', '.join(map(repr, unknown))}; "
                f"the Spotify simulator takes: {', '.join(cls.model_fields)}"
            )
        try:
            settings = cls.model_validate(sim)
        except ValidationError as error:
            problems = "; ".join(f"{'.'.join(map(str, e['loc']))}: {e['msg']}" for e in error.errors())
            raise DeviceError(f"{where}: {problems}") from None
        if settings.track is None and (settings.artist is not None or settings.is_playing):
            raise DeviceError(f"{where}: artist and is_playing = true need a track; add track = <title>")
        return settings


class SimPlayer:
    """The player's state and rules, without I/O. Each action returns the sentence to report."""

    def __init__(self, settings: SimSettings, rng: random.Random, instance: str = "spotify") -> None:
        self.catalog: tuple[CatalogEntry, ...] = tuple(settings.catalog or DEFAULT_CATALOG)
        self.rng = rng
        self.is_playing = settings.is_playing
        self.volume = settings.volume
        self.shuffle = settings.shuffle
        self.repeat: Repeat = settings.repeat
        self.queued: deque[CatalogEntry] = deque()
        self.context: list[CatalogEntry] = []
        self.order: list[int] = []
        """Play order of ``context`` (indices); a permutation while shuffling."""
        self.position = 0
        """Where in ``order`` the context is; a queued track plays without moving it."""
        self.current: CatalogEntry | None = None
        self.from_queue = False
        """The current track came from the queue, not from the context at ``position``."""
        self.autoplay = settings.autoplay
        self.track_seconds = settings.track_seconds
        self.progress = 0.0
        """Seconds into the current track (only the clock of ``track_seconds`` moves it)."""
        if settings.track is not None:
            start = self._initial_track(instance, settings.track, settings.artist)
            # A track set by hand plays within the whole catalog, so "next" has somewhere to go.
            self._load(list(self.catalog), self.catalog.index(start), playing=settings.is_playing)

    def _initial_track(self, instance: str, track: str, artist: str | None) -> CatalogEntry:
        for entry in self.catalog:
            if normalize(entry.track) == normalize(track) and (
                artist is None or normalize(entry.artist) == normalize(artist)
            ):
                return entry
        titles = ", ".join(repr(describe(entry)) for entry in self.catalog[:8])
        raise DeviceError(
            f"devices.{instance}.sim: track {track!r}{f' by {artist}' if artist else ''} is not in the "
            f"catalog; add it to sim.catalog or pick one of: {titles}"
        )

    def state(self) -> PlayerState:
        """The state ``get_state`` reports."""
        return PlayerState(
            is_playing=self.is_playing,
            volume=self.volume,
            track=self.current.track if self.current else None,
            artist=self.current.artist if self.current else None,
            shuffle=self.shuffle,
            repeat=self.repeat,
        )

    # Actions

    def play(self, query: str, kind: SearchKind = "any") -> str:
        """Play the best match for ``query`` in its context; raise when nothing matches."""
        cleaned, hinted = clean_query(query)
        if not cleaned:
            self._load(list(self.catalog), None)
            return f"Playing from the whole catalog: {self._now()}."
        match = self._best(query, cleaned, kind if kind != "any" else hinted)
        if match.kind == "track":
            entry = match.tracks[0]
            album = [e for e in self.catalog if entry.album is not None and e.album == entry.album]
            context = album or [entry]
            self._load(context, context.index(entry))
            return f"Playing {self._now()}."
        self._load(list(match.tracks), None)
        what = {"artist": "songs by", "album": "the album", "genre": "some"}[match.kind]
        return f"Playing {what} {match.name}: {self._now()}."

    def pause(self) -> str:
        """Pause; a no-op when nothing plays."""
        if not self.is_playing:
            return "Already paused." if self.current else "Nothing is playing."
        self.is_playing = False
        return f"Paused {self._now()}."

    def resume(self) -> str:
        """Resume the current track, or start the catalog when nothing is loaded (like Spotify's resume)."""
        if self.current is None:
            self._load(list(self.catalog), None)
            return f"Nothing was loaded, so playing from the catalog: {self._now()}."
        if self.is_playing:
            return f"Already playing {self._now()}."
        self.is_playing = True
        return f"Resumed {self._now()}."

    def next_track(self) -> str:
        """Skip forward: the queue, then the context, then repeat or autoplay."""
        self._need_track("next")
        return self._advance() or f"{self._now()} was the last track, so the music stopped."

    def tick(self, seconds: float) -> bool:
        """Let ``seconds`` of playing time pass; True when the music ran out (it stopped by itself)."""
        if self.track_seconds is None or not self.is_playing or self.current is None:
            return False
        self.progress += seconds
        while self.is_playing and self.progress >= self.track_seconds:
            left = self.progress - self.track_seconds  # into the next track
            if self.repeat != "track" and self._advance() is None:
                return True
            self.progress = left
        return False

    def _advance(self) -> str | None:
        """Move to the next track and play it; None when nothing comes next (playback stops)."""
        self.progress = 0.0
        if self.queued:
            self.current, self.from_queue = self.queued.popleft(), True
            self.is_playing = True
            return f"Playing {self._now()} (from the queue)."
        note = ""
        if self.position + 1 < len(self.order):
            self.position += 1
        elif self.repeat == "context":
            self.position, note = 0, " (repeating from the start)"
        elif not self.autoplay:
            self.is_playing = False
            return None
        elif (similar := self._autoplay()) is not None:
            self.context.append(similar)
            self.order.append(len(self.context) - 1)
            self.position, note = len(self.order) - 1, " (autoplay: the end was reached)"
        else:
            note = " again: the catalog has nothing else"
        self.current, self.from_queue = self.context[self.order[self.position]], False
        self.is_playing = True
        return f"Playing {self._now()}{note}."

    def previous_track(self) -> str:
        """Go back one track in the context; at its start, restart the track (or wrap on repeat)."""
        self._need_track("previous")
        note = ""
        if self.from_queue:
            pass  # back to the context track the queued one came after
        elif self.position > 0:
            self.position -= 1
        elif self.repeat == "context":
            self.position = len(self.order) - 1
        else:
            note = " from the beginning (it is the first track here)"
        self.current, self.from_queue = self.context[self.order[self.position]], False
        self.is_playing, self.progress = True, 0.0
        return f"Playing {self._now()}{note}."

    def set_volume(self, volume: int) -> str:
        """Set the volume in percent."""
        old, self.volume = self.volume, volume
        return volume_message(old, volume)

    def set_shuffle(self, shuffle: bool) -> str:
        """Shuffle the rest of the context (current track first), or go back to its own order."""
        changed, self.shuffle = shuffle != self.shuffle, shuffle
        if changed and self.context:
            current = self.order[self.position]
            self.order = self._play_order(len(self.context), current)
            self.position = self.order.index(current)
        return f"Shuffle {'on' if shuffle else 'off'}."

    def set_repeat(self, repeat: Repeat) -> str:
        """Set the repeat mode."""
        self.repeat = repeat
        return {"off": "Repeat off.", "track": "Repeating this track.", "context": "Repeating the context."}[
            repeat
        ]

    def queue(self, query: str) -> str:
        """Add the best matching track to the queue (an artist/album/genre adds its first track)."""
        cleaned, hinted = clean_query(query)
        if not cleaned:
            raise DeviceError("say what to queue: a track title, an artist, an album or a genre")
        entry = self._best(query, cleaned, hinted).tracks[0]
        self.queued.append(entry)
        return (
            f"Queued {describe(entry)}: it plays after the current track ({len(self.queued)} in the queue)."
        )

    def search(self, query: str, kind: SearchKind, limit: int) -> list[SearchHit]:
        """The best matches, as search hits; raise when nothing matches."""
        cleaned, hinted = clean_query(query)
        if not cleaned:
            raise DeviceError("say what to search for: a track title, an artist, an album or a genre")
        matches = find(self.catalog, cleaned, kind if kind != "any" else hinted)
        if not matches:
            raise self._not_found(query, kind)
        return [_hit(match) for match in matches[:limit]]

    # Helpers

    def _best(self, query: str, cleaned: str, kind: SearchKind) -> Match:
        matches = find(self.catalog, cleaned, kind)
        if not matches:
            raise self._not_found(query, kind)
        return matches[0]

    def _not_found(self, query: str, kind: SearchKind) -> DeviceError:
        what = "nothing" if kind == "any" else f"no {kind}"
        return DeviceError(
            f'found {what} matching "{query}"; nothing changed. Try {suggestions(self.catalog)}, '
            "or use search to see what there is"
        )

    def _load(self, tracks: list[CatalogEntry], start: int | None, *, playing: bool = True) -> None:
        """Make ``tracks`` the context and play from ``start`` (None: the first in play order)."""
        self.context = tracks
        self.order = self._play_order(len(tracks), start)
        self.position = self.order.index(start) if start is not None else 0
        self.current, self.from_queue = tracks[self.order[self.position]], False
        self.is_playing, self.progress = playing, 0.0

    def _play_order(self, size: int, first: int | None) -> list[int]:
        if not self.shuffle:
            return list(range(size))
        rest = [index for index in range(size) if index != first]
        self.rng.shuffle(rest)
        return ([first] if first is not None else []) + rest

    def _autoplay(self) -> CatalogEntry | None:
        """Similar music after the context ends: same genre first, tracks not yet in the context."""
        fresh = [entry for entry in self.catalog if entry not in self.context]
        candidates = fresh or [entry for entry in self.catalog if entry != self.current]
        if not candidates:
            return None
        genre = self.current.genre if self.current else None
        same_genre = [entry for entry in candidates if entry.genre == genre]
        pool = same_genre or candidates
        return self.rng.choice(pool) if self.shuffle else pool[0]

    def _need_track(self, which: str) -> None:
        if self.current is None:
            raise DeviceError(
                f"nothing is loaded, so there is no {which} track; use play to choose something"
            )

    def _now(self) -> str:
        return describe(self.current) if self.current else "nothing"


def _hit(match: Match) -> SearchHit:
    first = match.tracks[0]
    if match.kind == "track":
        return SearchHit(kind="track", name=match.name, artist=first.artist, album=first.album)
    if match.kind == "album":
        return SearchHit(kind="album", name=match.name, artist=first.artist)
    return SearchHit(kind=match.kind, name=match.name)


class SimBackend(SpotifyBackend):
    """The ``sim`` backend: a :class:`SimPlayer` behind the :class:`SpotifyBackend` interface."""

    simulated = True

    def __init__(self, instance: str, settings: SimSettings, seed: int | str | None = None) -> None:
        self.instance = instance
        # Seeded by the instance name: a benchmark run that shuffles can be repeated exactly.
        self.player = SimPlayer(settings, random.Random(instance if seed is None else seed), instance)
        self.ending = PlaybackEndNotifier(instance)
        self._clock: PeriodicTask | None = None
        if settings.track_seconds is not None:
            period = min(CLOCK_PERIOD, settings.track_seconds / 4)
            self._clock = PeriodicTask(f"{instance} clock", period, self._tick)

    async def start(self) -> None:
        """Start the clock when tracks have a length (``sim.track_seconds``)."""
        if self._clock is not None:
            self._clock.start()

    async def close(self) -> None:
        """Stop the clock."""
        if self._clock is not None:
            await self._clock.stop()

    async def _tick(self, seconds: float) -> None:
        last = self.player.current
        if self.player.tick(seconds) and last is not None:
            self.ending.ended(last.track, last.artist)

    async def state(self) -> PlayerState:
        """The simulated player's state."""
        return self.player.state()

    def _report(self, message: str) -> PlayerReport:
        return PlayerReport(message=message, state=self.player.state())

    async def play(self, query: str, kind: SearchKind = "any") -> PlayerReport:
        """Play the best catalog match for ``query``."""
        return self._report(self.player.play(query, kind))

    async def pause(self) -> PlayerReport:
        """Pause."""
        return self._report(self.player.pause())

    async def resume(self) -> PlayerReport:
        """Resume (or start the catalog when nothing is loaded)."""
        return self._report(self.player.resume())

    async def next_track(self) -> PlayerReport:
        """Skip forward."""
        return self._report(self.player.next_track())

    async def previous_track(self) -> PlayerReport:
        """Go back."""
        return self._report(self.player.previous_track())

    async def set_volume(self, volume: int) -> PlayerReport:
        """Set the volume."""
        return self._report(self.player.set_volume(volume))

    async def set_shuffle(self, shuffle: bool) -> PlayerReport:
        """Turn shuffle on or off."""
        return self._report(self.player.set_shuffle(shuffle))

    async def set_repeat(self, repeat: Repeat) -> PlayerReport:
        """Set the repeat mode."""
        return self._report(self.player.set_repeat(repeat))

    async def queue(self, query: str) -> PlayerReport:
        """Queue the best matching track."""
        return self._report(self.player.queue(query))

    async def search(self, query: str, kind: SearchKind = "any", limit: int = 5) -> SearchResults:
        """Search the catalog."""
        hits = self.player.search(query, kind, limit)
        return SearchResults(message=f'{len(hits)} result(s) for "{query}".', hits=hits)
