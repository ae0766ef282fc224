"""The settings of one ``spotify`` instance: the keys of ``[devices.NAME]`` besides driver, backend and sim."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from rosaos.drivers import DeviceSettings

DEFAULT_REDIRECT_URI = "http://127.0.0.1:8888/callback"
"""Spotify accepts plain http only for loopback addresses; register exactly this in the app."""


class SpotifySettings(DeviceSettings):
    """Only the ``real`` backend and ``rosaos devices login`` use these; the simulator needs none."""

    client_id: str | None = Field(
        default=None,
        description="Client ID of your Spotify app (https://developer.spotify.com/dashboard). "
        "PKCE needs no client secret.",
    )
    redirect_uri: str = Field(
        default=DEFAULT_REDIRECT_URI,
        description="A Redirect URI registered in the app, character for character.",
    )
    device: str | None = Field(
        default=None,
        description="Spotify Connect device to play on, by name or id (as `get_state` and the Spotify "
        "app show it). Default: whichever device is active.",
    )
    market: Annotated[str, Field(pattern=r"^[A-Z]{2}$")] | None = Field(
        default=None,
        description="ISO 3166 country code for search results (e.g. DE). Default: the account's country.",
    )
    timeout: Annotated[float, Field(gt=0, le=120)] = Field(
        default=10.0, description="Seconds one Spotify request may take."
    )
    watch_seconds: Annotated[float, Field(ge=0, le=3600)] = Field(
        default=10.0,
        description="How often to read the player to notice the music ending by itself "
        "(the playback_ended notice); 0 turns the watcher off.",
    )
