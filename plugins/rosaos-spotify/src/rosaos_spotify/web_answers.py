"""Reading the Spotify Web API's answers: the player state, search results, what to play.

Pure functions over the JSON spotipy returns (``GET /me/player``, ``GET /search``), kept apart
from :mod:`rosaos_spotify.web_api` so the shapes Spotify answers in are in one place.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rosaos.drivers import DeviceError
from rosaos_spotify.backend import PlayerState, SearchHit


@dataclass(frozen=True)
class PlayTarget:
    """What a query resolved to, as ``start_playback`` arguments, and how to report it."""

    description: str
    context_uri: str | None = None
    uris: list[str] | None = None
    offset: dict[str, str] | None = None
    track: str | None = None
    """The title that will play, when known (a track; the first of a genre's tracks)."""
    artist: str | None = None


def state_of(playback: dict[str, Any]) -> PlayerState:
    """The :class:`PlayerState` in a ``GET /me/player`` answer."""
    item = playback.get("item") or {}
    device = playback.get("device") or {}
    repeat = playback.get("repeat_state")
    return PlayerState(
        is_playing=bool(playback.get("is_playing")),
        volume=device.get("volume_percent") or 0,
        track=item.get("name"),
        artist=artists_of(item) if item else None,
        shuffle=bool(playback.get("shuffle_state")),
        repeat=repeat if repeat in ("off", "track", "context") else "off",
    )


def section(found: dict[str, Any] | None, kind: str) -> list[dict[str, Any]]:
    """The items of one kind in a search answer (``{"tracks": {"items": [...]}}``), skipping nulls."""
    return [item for item in ((found or {}).get(f"{kind}s") or {}).get("items") or [] if item]


def artists_of(item: dict[str, Any]) -> str | None:
    """The artists of a track or album, comma-separated ("Daft Punk, Pharrell Williams")."""
    names = [artist.get("name") for artist in item.get("artists") or [] if artist.get("name")]
    return ", ".join(names) or (item.get("show") or {}).get("name")  # a podcast episode: the show


def describe_track(track: dict[str, Any]) -> str:
    """How a track is named in replies: "Clair de Lune by Claude Debussy"."""
    return f"{track.get('name')} by {artists_of(track)}"


def play_target(kind: str, item: dict[str, Any]) -> PlayTarget:
    """How to play a search result: an artist or album as a context, a track within its album."""
    if kind == "artist":
        return PlayTarget(f"songs by {item['name']}", context_uri=item["uri"])
    if kind == "album":
        return PlayTarget(f"the album {item['name']} by {artists_of(item)}", context_uri=item["uri"])
    album_uri = (item.get("album") or {}).get("uri")
    # Within its album, so "next" goes on to the album's next song, as in the Spotify app.
    if album_uri:
        body: dict[str, Any] = {"context_uri": album_uri, "offset": {"uri": item["uri"]}}
    else:
        body = {"uris": [item["uri"]]}
    return PlayTarget(describe_track(item), track=item["name"], artist=artists_of(item), **body)


def search_hit(kind: str, item: dict[str, Any]) -> SearchHit:
    """A search result item as a :class:`SearchHit`."""
    if kind == "track":
        album = (item.get("album") or {}).get("name")
        return SearchHit(kind="track", name=item["name"], artist=artists_of(item), album=album)
    if kind == "album":
        return SearchHit(kind="album", name=item["name"], artist=artists_of(item))
    return SearchHit(kind="artist", name=item["name"])


def not_found(query: str) -> DeviceError:
    """The error for a search that found nothing: what to try instead."""
    return DeviceError(
        f'Spotify found nothing for "{query}"; nothing changed. Try the exact title, an artist or '
        "album name, or a genre such as jazz, classical, rock or pop"
    )
