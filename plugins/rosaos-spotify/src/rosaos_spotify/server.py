"""The MCP tools of one Spotify instance: what a process agent holding the device can call.

Every action returns a :class:`PlayerReport`: a sentence saying what happened ("Playing Clair de
Lune by Claude Debussy.") and the player state afterwards, with the keys of ``get_state``. A
query that finds nothing fails with a message listing what to try, and changes nothing.
"""

from __future__ import annotations

from typing import Annotated

from fastmcp import FastMCP
from pydantic import Field

from rosaos import drivers
from rosaos.drivers import DeviceContext
from rosaos_spotify.backend import PlayerReport, PlayerState, Repeat, SearchResults, SpotifyBackend
from rosaos_spotify.catalog import SearchKind

# Annotations, per MCP: nothing here is destructive (music can always be played again);
# setting a value twice is the same as once, relative and "start over" actions are not.
READ_ONLY, SET, CHANGE = drivers.READ_ONLY, drivers.SETS, drivers.CHANGES

Query = Annotated[
    str,
    Field(
        min_length=1,
        max_length=200,
        description="What to find: a song title, an artist, an album or a genre, as the user said it, "
        'e.g. "Clair de Lune", "Miles Davis", "the album Abbey Road", "some jazz".',
    ),
]
Kind = Annotated[
    SearchKind,
    Field(description='What the query names; "any" (default) lets Spotify\'s best match decide.'),
]
Volume = Annotated[int, Field(ge=0, le=100, description="Volume in percent, 0-100.")]
VolumeChange = Annotated[
    int, Field(ge=-100, le=100, description="Percentage points to add; negative is quieter. Kept 0-100.")
]
Limit = Annotated[int, Field(ge=1, le=20, description="How many results, 1-20.")]


def build_server(ctx: DeviceContext, backend: SpotifyBackend) -> FastMCP:
    """Build the FastMCP server for one Spotify instance on a started backend."""
    mcp = FastMCP(name=ctx.instance, instructions=f"{ctx.description} (Spotify playback).")

    @mcp.tool(annotations=READ_ONLY)
    async def get_state() -> PlayerState:
        """Read the player: is_playing, volume (0-100), track and artist (null when nothing is
        loaded), shuffle, repeat (off, track or context)."""
        return await backend.state()

    @mcp.tool(annotations=CHANGE)
    async def play(query: Query, kind: Kind = "any") -> PlayerReport:
        """Find music and play it now, replacing what plays: a song (within its album), all songs
        of an artist or album, or tracks of a genre ("some jazz").

        Pass the user's words as the query; set kind only when they say it ("the album ...").
        """
        return await backend.play(query, kind)

    @mcp.tool(annotations=SET)
    async def pause() -> PlayerReport:
        """Pause the music. Nothing happens if it is already paused."""
        return await backend.pause()

    @mcp.tool(annotations=SET)
    async def resume() -> PlayerReport:
        """Resume the paused track where it stopped (use play to choose something else)."""
        return await backend.resume()

    @mcp.tool(annotations=CHANGE)
    async def next_track() -> PlayerReport:
        """Skip to the next track: the queue first, then the current album, artist or genre."""
        return await backend.next_track()

    @mcp.tool(annotations=CHANGE)
    async def previous_track() -> PlayerReport:
        """Go back to the previous track of the current album, artist or genre."""
        return await backend.previous_track()

    @mcp.tool(annotations=SET)
    async def set_volume(volume: Volume) -> PlayerReport:
        """Set the volume to a level in percent (0-100), e.g. "set the volume to 70"."""
        return await backend.set_volume(volume)

    @mcp.tool(annotations=CHANGE)
    async def change_volume(delta: VolumeChange) -> PlayerReport:
        """Make the music louder or quieter by some points: +15 for "turn it up", -15 for "turn it
        down"; about 5 for "a bit", 30 for "a lot". The result stays within 0-100."""
        return await backend.change_volume(delta)

    @mcp.tool(annotations=SET)
    async def set_shuffle(shuffle: bool) -> PlayerReport:
        """Turn shuffle on (true) or off (false) for the current album, artist or genre."""
        return await backend.set_shuffle(shuffle)

    @mcp.tool(annotations=SET)
    async def set_repeat(repeat: Repeat) -> PlayerReport:
        """Set repeat: "track" repeats this song, "context" the album/artist/genre, "off" stops repeating."""
        return await backend.set_repeat(repeat)

    @mcp.tool(annotations=CHANGE)
    async def queue(query: Query) -> PlayerReport:
        """Add one song to the queue: it plays after the current one, without interrupting it."""
        return await backend.queue(query)

    @mcp.tool(annotations=READ_ONLY)
    async def search(query: Query, kind: Kind = "any", limit: Limit = 5) -> SearchResults:
        """Look up songs, artists, albums or genres without playing anything, best first.

        Use it to answer "what is there by ..." or to check a title before playing it.
        """
        return await backend.search(query, kind, limit)

    return mcp
