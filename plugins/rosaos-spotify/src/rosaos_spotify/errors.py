"""Spotify's failures, each turned into a :class:`DeviceError` that says what to do.

These are the ones Spotify users actually hit: no active device (Spotify plays *on* a phone,
computer or speaker, and none is open), a Free account (the Web API's player commands are
Premium-only), a login that expired or was revoked, and rate limiting.
"""

from __future__ import annotations

import requests
from spotipy.exceptions import SpotifyException
from spotipy.oauth2 import SpotifyOauthError

from rosaos.drivers import DeviceError
from rosaos_spotify.auth import NotLoggedIn

NO_ACTIVE_DEVICE = "NO_ACTIVE_DEVICE"
PREMIUM_REQUIRED = "PREMIUM_REQUIRED"
RESTRICTION_VIOLATED = "RESTRICTION_VIOLATED"
"""Spotify's answer to a command that makes no sense now: pause while paused, skip at the end."""
VOLUME_CONTROL_DISALLOW = "VOLUME_CONTROL_DISALLOW"


class SpotifyError(DeviceError):
    """A :class:`DeviceError` from Spotify that keeps the HTTP status and Spotify's ``reason``,
    so the backend can handle the harmless ones (pause while paused, nothing active to pause)."""

    def __init__(self, message: str, status: int | None = None, reason: str | None = None) -> None:
        super().__init__(message)
        self.status = status
        self.reason = reason


def reason_of(error: BaseException) -> str | None:
    """The ``reason`` Spotify gave for a refused player command (``NO_ACTIVE_DEVICE``...), if any."""
    if isinstance(error, SpotifyException):
        return str(error.reason) if error.reason else None
    return None


def login_hint(instance: str) -> str:
    """The command that fixes a missing or dead login."""
    return f"run `rosaos devices login {instance}` on the machine that serves it, then try again"


def spotify_error(error: BaseException, instance: str) -> SpotifyError:
    """Translate a spotipy (or network) failure into a :class:`SpotifyError` with a fix-it message."""
    where = f"[devices.{instance}]"
    if isinstance(error, NotLoggedIn):
        return SpotifyError(f"{instance} is not logged in to Spotify: {login_hint(instance)}")
    if isinstance(error, SpotifyOauthError):
        return SpotifyError(_oauth_error(error, instance, where))
    if isinstance(error, SpotifyException):
        return SpotifyError(
            _api_error(error, instance, where), status=error.http_status, reason=reason_of(error)
        )
    if isinstance(error, requests.Timeout):
        return SpotifyError("Spotify did not answer in time; check the internet connection and try again")
    if isinstance(error, requests.RequestException):
        return SpotifyError(f"cannot reach Spotify ({type(error).__name__}); check the internet connection")
    return SpotifyError(f"Spotify failed: {type(error).__name__}: {error}")


def _oauth_error(error: SpotifyOauthError, instance: str, where: str) -> str:
    code = getattr(error, "error", None)
    if code == "invalid_grant":
        return f"the saved Spotify login of {instance} has expired or was revoked: {login_hint(instance)}"
    if code == "invalid_client":
        return (
            f"Spotify does not know the client_id in {where}: copy the Client ID of your app from "
            "https://developer.spotify.com/dashboard, then log in again"
        )
    return f"Spotify refused the login ({code or error}): {login_hint(instance)}"


def _api_error(error: SpotifyException, instance: str, where: str) -> str:
    status, reason = error.http_status, reason_of(error)
    message = _spotify_message(error)
    if status == 401:
        return f"Spotify rejected the access token of {instance} ({message}): {login_hint(instance)}"
    if reason == NO_ACTIVE_DEVICE or (status == 404 and "device" in message.lower()):
        return (
            "Spotify has no active device to play on: open Spotify on a phone, computer or speaker "
            f'and play something once, or set device = "<device name>" in {where} to always use one'
        )
    if reason == PREMIUM_REQUIRED:
        return (
            "controlling playback needs Spotify Premium, and this account is Spotify Free: "
            f"upgrade it, or log {instance} in with a Premium account (`rosaos devices login {instance}`)"
        )
    if reason == VOLUME_CONTROL_DISALLOW:
        return (
            "the playing device does not let Spotify change its volume (phones often do not): "
            f"use the device's own volume buttons, or play on another device (device = ... in {where})"
        )
    if status == 429:
        after = (error.headers or {}).get("Retry-After")
        wait = f"in {after} s" if after else "in a minute"
        return f"Spotify is rate-limiting requests; try again {wait}"
    if status == 403:
        return f"Spotify does not allow that right now: {message}"
    if status >= 500:
        return f"Spotify is having trouble (HTTP {status}); try again in a moment"
    return f"Spotify refused the request (HTTP {status}): {message}"


def _spotify_message(error: SpotifyException) -> str:
    # spotipy prefixes the message with the URL ("https://api.spotify.com/v1/me/player/play:\n msg").
    text = str(error.msg or "")
    return text.rsplit(":\n", 1)[-1].strip() or "no details"
