"""Spotify OAuth for rosaOS: authorization code with PKCE, and where the tokens are kept.

PKCE needs only the app's *client id* (no client secret on the machine), which is what Spotify
recommends for apps that run on the user's own computer. ``rosaos devices login NAME`` runs the
browser half once (:mod:`rosaos_spotify.login`); afterwards the refresh token in
``<data dir>/drivers/spotify/<instance>.json`` (owner-only, mode 0600) keeps the driver logged in.

A device server must never stop to ask for a login: :class:`HeadlessPKCE` raises
:class:`NotLoggedIn` where spotipy would open a browser or wait on stdin.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path
from typing import Any

from spotipy.cache_handler import CacheHandler
from spotipy.oauth2 import SpotifyOauthError, SpotifyPKCE

DRIVER_DIR = ("drivers", "spotify")
SCOPES = (
    "user-read-playback-state",  # get_state: what plays, where, at what volume
    "user-modify-playback-state",  # play, pause, skip, volume, shuffle, repeat, queue
    "user-read-currently-playing",
    "user-read-private",  # the account's product (Free or Premium), checked at login
)
"""What rosaOS asks the user to allow. A saved login with fewer scopes counts as logged out."""


class NotLoggedIn(SpotifyOauthError):
    """No usable saved login: the user must run ``rosaos devices login NAME``."""


def token_path(data_dir: Path, instance: str) -> Path:
    """Where ``instance``'s Spotify tokens are kept: ``<data dir>/drivers/spotify/<instance>.json``."""
    return data_dir.joinpath(*DRIVER_DIR, f"{instance}.json")


class TokenCache(CacheHandler):
    """spotipy's token cache, as one JSON file readable by its owner only.

    Unlike spotipy's ``CacheFileHandler`` (write, then chmod), the file is created 0600 and
    swapped in atomically, so the refresh token is never world-readable, not even for a moment,
    and a crash mid-write cannot leave half a token behind.
    """

    def __init__(self, path: Path) -> None:
        self.path = path

    def get_cached_token(self) -> dict[str, Any] | None:
        """The saved token info, or None when there is none (or it is unreadable)."""
        try:
            data = json.loads(self.path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        return data if isinstance(data, dict) else None

    def save_token_to_cache(self, token_info: dict[str, Any]) -> None:
        """Write ``token_info`` (access and refresh token, expiry, scopes) with mode 0600."""
        self.path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        # mkstemp creates the file 0600; os.replace makes the new content appear all at once.
        descriptor, temporary = tempfile.mkstemp(prefix=".token-", dir=self.path.parent)
        try:
            with os.fdopen(descriptor, "w", encoding="utf-8") as file:
                json.dump(token_info, file)
            os.chmod(temporary, 0o600)
            os.replace(temporary, self.path)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(temporary)
            raise

    def has_login(self) -> bool:
        """Whether a refresh token is saved (it may still have been revoked on Spotify's side)."""
        token = self.get_cached_token()
        return bool(token and token.get("refresh_token"))


class HeadlessPKCE(SpotifyPKCE):
    """spotipy's PKCE flow that never prompts: no browser, no local server, no stdin."""

    def get_authorization_code(self, response: str | None = None) -> str:
        """The code from a pasted redirect URL; without one, raise :class:`NotLoggedIn`."""
        if response:
            return str(self.parse_response_code(response))
        raise NotLoggedIn(
            "no saved Spotify login with the permissions rosaOS needs",
            error="not_logged_in",
        )


def auth_manager(client_id: str, redirect_uri: str, cache: TokenCache, timeout: float) -> HeadlessPKCE:
    """The PKCE manager a backend or the login flow uses: rosaOS's scopes, ``cache`` for tokens."""
    return HeadlessPKCE(
        client_id=client_id,
        redirect_uri=redirect_uri,
        scope=list(SCOPES),
        cache_handler=cache,
        open_browser=False,
        requests_timeout=timeout,
    )
