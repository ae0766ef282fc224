"""``rosaos devices login`` for Spotify: PKCE by copy and paste, the token exchange mocked.

The exchange at accounts.spotify.com is the only cloud edge; ``responses`` plays Spotify's part.
"""

from __future__ import annotations

import base64
import hashlib
import json
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlparse

import pytest
import responses

from rosaos_spotify import login as login_module
from rosaos_spotify.auth import SCOPES, TokenCache, token_path
from rosaos_spotify.login import code_from_redirect, login_interactive
from rosaos_spotify.settings import SpotifySettings

FIXTURES = Path(__file__).parent / "fixtures"
TOKEN_URL = "https://accounts.spotify.com/api/token"
ME_URL = "https://api.spotify.com/v1/me/"  # spotipy asks for "me/"
REDIRECT = "http://127.0.0.1:8888/callback"
STATE = "state-of-this-attempt"
SETTINGS = SpotifySettings(client_id="abc123")
TOKENS = {
    "access_token": "BQD-access",
    "token_type": "Bearer",
    "scope": " ".join(SCOPES),
    "expires_in": 3600,
    "refresh_token": "AQB-refresh",
}


class Terminal:
    """The user's side of the login: what was printed, and what they paste when asked."""

    def __init__(self, answer: str | None = None) -> None:
        self.printed: list[str] = []
        self.answer = answer

    def output(self, text: str) -> None:
        self.printed.append(text)

    def input(self, prompt: str) -> str:
        self.printed.append(prompt)
        if self.answer is None:
            raise EOFError
        return self.answer

    @property
    def text(self) -> str:
        return "\n".join(self.printed)

    def authorize_url(self) -> str:
        return next(word for word in self.text.split() if word.startswith("https://accounts.spotify.com"))


@pytest.fixture(autouse=True)
def fixed_state(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(login_module.secrets, "token_urlsafe", lambda size: STATE)


@pytest.fixture
def accounts() -> Iterator[responses.RequestsMock]:
    with responses.RequestsMock(assert_all_requests_are_fired=False) as mock:
        yield mock


def run(terminal: Terminal, data_dir: Path, settings: SpotifySettings = SETTINGS) -> int:
    return login_interactive(settings, data_dir, "spotify", input=terminal.input, output=terminal.output)


def test_login_prints_the_url_exchanges_the_pasted_code_and_saves_the_tokens(
    tmp_path: Path, accounts: responses.RequestsMock
) -> None:
    exchange = accounts.post(TOKEN_URL, json=TOKENS)
    accounts.get(ME_URL, json=json.loads((FIXTURES / "me_premium.json").read_text(encoding="utf-8")))
    terminal = Terminal(f"{REDIRECT}?code=AQC-the-code&state={STATE}")

    assert run(terminal, tmp_path) == 0

    query = parse_qs(urlparse(terminal.authorize_url()).query)
    assert query["client_id"] == ["abc123"]
    assert query["redirect_uri"] == [REDIRECT]
    assert query["state"] == [STATE]
    assert query["code_challenge_method"] == ["S256"]
    assert set(query["scope"][0].split()) == set(SCOPES)
    sent = parse_qs(str(exchange.calls[0].request.body))
    assert (sent["grant_type"], sent["code"], sent["client_id"]) == (
        ["authorization_code"],
        ["AQC-the-code"],
        ["abc123"],
    )
    # PKCE: the verifier sent now hashes to the challenge that was in the URL.
    digest = hashlib.sha256(sent["code_verifier"][0].encode()).digest()
    assert base64.urlsafe_b64encode(digest).decode().rstrip("=") == query["code_challenge"][0]
    saved = TokenCache(token_path(tmp_path, "spotify"))
    assert (saved.get_cached_token() or {})["refresh_token"] == "AQB-refresh"
    assert stat.S_IMODE(saved.path.stat().st_mode) == 0o600
    assert "Account: Maria." in terminal.text


def test_a_free_account_is_warned_that_playback_needs_premium(
    tmp_path: Path, accounts: responses.RequestsMock
) -> None:
    accounts.post(TOKEN_URL, json=TOKENS)
    accounts.get(ME_URL, json={"display_name": "Maria", "product": "free"})
    terminal = Terminal(f"{REDIRECT}?code=c&state={STATE}")
    assert run(terminal, tmp_path) == 0
    assert "needs Spotify Premium" in terminal.text


def test_without_a_client_id_it_explains_how_to_make_an_app(tmp_path: Path) -> None:
    terminal = Terminal()
    assert run(terminal, tmp_path, SpotifySettings()) == 2
    assert "https://developer.spotify.com/dashboard" in terminal.text
    assert f"Redirect URI to it, exactly: {REDIRECT}" in terminal.text
    assert 'client_id = "<Client ID>"' in terminal.text


def test_an_expired_code_says_to_run_the_login_again(
    tmp_path: Path, accounts: responses.RequestsMock
) -> None:
    accounts.post(
        TOKEN_URL,
        status=400,
        json={"error": "invalid_grant", "error_description": "Invalid authorization code"},
    )
    terminal = Terminal(f"{REDIRECT}?code=old&state={STATE}")
    assert run(terminal, tmp_path) == 1
    assert "expired or was already used" in terminal.text
    assert not token_path(tmp_path, "spotify").exists()


def test_a_redirect_uri_mismatch_says_to_register_it(
    tmp_path: Path, accounts: responses.RequestsMock
) -> None:
    accounts.post(
        TOKEN_URL, status=400, json={"error": "invalid_grant", "error_description": "Invalid redirect URI"}
    )
    terminal = Terminal(f"{REDIRECT}?code=c&state={STATE}")
    assert run(terminal, tmp_path) == 1
    assert f"redirect_uri '{REDIRECT}' is not one of the app's Redirect URIs" in terminal.text


def test_an_unknown_client_id_says_where_to_copy_it(tmp_path: Path, accounts: responses.RequestsMock) -> None:
    accounts.post(
        TOKEN_URL, status=400, json={"error": "invalid_client", "error_description": "Invalid client"}
    )
    terminal = Terminal(f"{REDIRECT}?code=c&state={STATE}")
    assert run(terminal, tmp_path) == 1
    assert "does not know client_id 'abc123'" in terminal.text


def test_cancelling_saves_nothing(tmp_path: Path) -> None:
    terminal = Terminal(answer=None)  # Ctrl-D at the prompt
    assert run(terminal, tmp_path) == 1
    assert "Login cancelled" in terminal.text
    assert not token_path(tmp_path, "spotify").exists()


@pytest.mark.parametrize(
    ("pasted", "problem"),
    [
        ("", "nothing was pasted"),
        ("https://example.com/somewhere", "not the address Spotify redirected to"),
        (f"{REDIRECT}?error=access_denied&state={STATE}", "you pressed Cancel"),
        (f"{REDIRECT}?code=c&state=another-attempt", "belongs to another login attempt"),
    ],
)
def test_a_wrong_paste_is_explained(pasted: str, problem: str) -> None:
    with pytest.raises(login_module.LoginError, match=problem):
        code_from_redirect(pasted, STATE, REDIRECT)


def test_the_pasted_address_may_be_quoted_or_padded() -> None:
    assert code_from_redirect(f'  "{REDIRECT}?code=xyz&state={STATE}"\n', STATE, REDIRECT) == "xyz"


def test_a_wrong_paste_makes_no_request(tmp_path: Path, accounts: Any) -> None:
    terminal = Terminal("AQC-just-the-code")
    assert run(terminal, tmp_path) == 1
    assert len(accounts.calls) == 0
