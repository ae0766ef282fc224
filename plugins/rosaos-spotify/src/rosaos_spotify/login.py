"""``rosaos devices login NAME`` for Spotify: the PKCE login, done by copy and paste.

It works on a headless machine (a robot, a server over SSH): rosaOS prints the authorization
URL, the user opens it in a browser anywhere, approves, and pastes back the address the browser
was sent to (``<redirect_uri>?code=...``; the page itself need not load). rosaOS exchanges the
code for tokens at accounts.spotify.com and saves them 0600 in the data directory.
"""

from __future__ import annotations

import builtins
import secrets
from collections.abc import Callable
from pathlib import Path
from urllib.parse import parse_qs, urlparse

import requests
import spotipy
from spotipy.oauth2 import SpotifyOauthError

from rosaos_spotify.auth import TokenCache, auth_manager, token_path
from rosaos_spotify.settings import SpotifySettings

DASHBOARD = "https://developer.spotify.com/dashboard"

SETUP_HELP = """\
{instance} has no client_id. rosaOS controls Spotify through a Spotify app of your own (free):
  1. Open {dashboard}, log in, and create an app; tick "Web API".
  2. Add this Redirect URI to it, exactly: {redirect_uri}
  3. Put the app's Client ID in rosaos.toml:
       [devices.{instance}]
       driver = "spotify"
       backend = "real"
       client_id = "<Client ID>"
  4. Run `rosaos devices login {instance}` again."""


class LoginError(Exception):
    """A pasted answer that cannot be used; the message says what to paste instead."""


def login_interactive(
    settings: SpotifySettings,
    data_dir: Path,
    instance: str = "spotify",
    *,
    input: Callable[[str], str] = builtins.input,
    output: Callable[[str], None] = print,
) -> int:
    """Log ``instance`` in to Spotify by copy and paste, and save the tokens. Returns the exit code.

    0: logged in (tokens saved); 1: the login failed or was cancelled (nothing saved);
    2: ``client_id`` is not configured (the output says how to get one).
    """
    if not settings.client_id:
        output(SETUP_HELP.format(instance=instance, dashboard=DASHBOARD, redirect_uri=settings.redirect_uri))
        return 2
    cache = TokenCache(token_path(data_dir, instance))
    manager = auth_manager(settings.client_id, settings.redirect_uri, cache, settings.timeout)
    state = secrets.token_urlsafe(16)  # ties the pasted answer to this attempt
    output(
        f"1. Open this address in a browser (on any computer or phone) and log in to Spotify:\n\n"
        f"   {manager.get_authorize_url(state=state)}\n\n"
        f"2. After you agree, the browser goes to {settings.redirect_uri}?code=...\n"
        "   The page may not load; that is fine.\n"
        "3. Copy the whole address from the browser's address bar and paste it here."
    )
    try:
        pasted = input("Address: ")
    except (EOFError, KeyboardInterrupt):
        output("\nLogin cancelled; nothing was saved.")
        return 1
    try:
        code = code_from_redirect(pasted, state, settings.redirect_uri)
        manager.get_access_token(code=code, check_cache=False)
    except LoginError as error:
        output(f"error: {error}")
        return 1
    except SpotifyOauthError as error:
        output(f"error: {exchange_problem(error, settings, instance)}")
        return 1
    except requests.RequestException as error:
        output(f"error: cannot reach accounts.spotify.com ({type(error).__name__}); check the connection")
        return 1
    output(f"Logged in. The login is saved in {cache.path} (readable by you only).")
    output(_account_note(manager))
    output(
        f'Next: make sure [devices.{instance}] has backend = "real", then run '
        f"`rosaos devices check {instance}`."
    )
    return 0


def code_from_redirect(pasted: str, state: str, redirect_uri: str) -> str:
    """The authorization code in the address the browser was sent to; :class:`LoginError` if none."""
    text = pasted.strip().strip("'\"")
    if not text:
        raise LoginError("nothing was pasted; run the command again and paste the address")
    params = {key: values[0] for key, values in parse_qs(urlparse(text).query).items()}
    if "error" in params:
        reason = params["error"]
        hint = (
            "you pressed Cancel on Spotify's page" if reason == "access_denied" else "see the message above"
        )
        raise LoginError(f"Spotify did not grant access ({reason}: {hint}); run the command again to retry")
    if "code" not in params:
        raise LoginError(
            f"that is not the address Spotify redirected to: it starts with {redirect_uri}?code= "
            "and is in the address bar after you agree"
        )
    if params.get("state") != state:
        raise LoginError(
            "that address belongs to another login attempt; use the address from this attempt's link"
        )
    return params["code"]


def exchange_problem(error: SpotifyOauthError, settings: SpotifySettings, instance: str) -> str:
    """What went wrong when trading the code for tokens, and what to do about it."""
    code = getattr(error, "error", None)
    description = str(getattr(error, "error_description", None) or "")
    if code == "invalid_client":
        return f"Spotify does not know client_id {settings.client_id!r}: copy the Client ID from {DASHBOARD}"
    if code == "invalid_grant" and "redirect" in description.lower():
        return (
            f"redirect_uri {settings.redirect_uri!r} is not one of the app's Redirect URIs: add it in "
            f"{DASHBOARD} (character for character), or set redirect_uri in [devices.{instance}]"
        )
    if code == "invalid_grant":
        return (
            "the code has expired or was already used (it is valid for a few minutes, once): "
            f"run `rosaos devices login {instance}` again and paste the new address right away"
        )
    return f"Spotify refused the login: {code or error} {description}".strip()


def _account_note(manager: object) -> str:
    """Who logged in, and a warning if the account cannot control playback (Spotify Free)."""
    try:
        user = spotipy.Spotify(auth_manager=manager, requests_timeout=10, retries=0).current_user() or {}
    except Exception as error:  # the login itself worked; this is only a courtesy check
        return f"(Could not read the account details: {type(error).__name__}.)"
    name = user.get("display_name") or user.get("id") or "unknown"
    if user.get("product") not in (None, "premium"):
        return (
            f"Account: {name} (Spotify {user.get('product')}). Controlling playback through the Web API "
            "needs Spotify Premium: play, pause, skip and volume will be refused until it has it."
        )
    return f"Account: {name}."
