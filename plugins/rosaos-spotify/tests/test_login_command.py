"""``rosaos devices login NAME``: core's generic command reaching this driver's login hook."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
import responses
from typer.testing import CliRunner

from rosaos.cli import app
from rosaos_spotify import login as login_module
from rosaos_spotify.auth import SCOPES, TokenCache, token_path

REDIRECT = "http://127.0.0.1:8888/callback"


def config(tmp_path: Path, devices: str) -> Path:
    path = tmp_path / "rosaos.toml"
    path.write_text(f'data_dir = "{tmp_path / "data"}"\n{devices}', encoding="utf-8")
    return path


@pytest.fixture
def accounts() -> Iterator[responses.RequestsMock]:
    with responses.RequestsMock(assert_all_requests_are_fired=False) as mock:
        yield mock


def test_login_saves_the_token_in_the_data_dir(
    tmp_path: Path, accounts: responses.RequestsMock, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(login_module.secrets, "token_urlsafe", lambda size: "s1")
    accounts.post(
        "https://accounts.spotify.com/api/token",
        json={
            "access_token": "a",
            "token_type": "Bearer",
            "expires_in": 3600,
            "refresh_token": "r",
            "scope": " ".join(SCOPES),
        },
    )
    accounts.get("https://api.spotify.com/v1/me/", json={"display_name": "Maria", "product": "premium"})
    path = config(tmp_path, '[devices.music]\ndriver = "spotify"\nbackend = "real"\nclient_id = "abc123"\n')

    result = CliRunner().invoke(
        app, ["devices", "login", "music", "--config", str(path)], input=f"{REDIRECT}?code=c&state=s1\n"
    )

    assert result.exit_code == 0, result.output
    assert "https://accounts.spotify.com/authorize?client_id=abc123" in result.output
    assert TokenCache(token_path(tmp_path / "data", "music")).has_login()


def test_login_without_client_id_explains_the_setup(tmp_path: Path) -> None:
    path = config(tmp_path, '[devices.spotify]\ndriver = "spotify"\n')
    result = CliRunner().invoke(app, ["devices", "login", "spotify", "--config", str(path)])
    assert result.exit_code == 2
    assert "has no client_id" in result.output


def test_login_for_an_unknown_device_names_the_known_ones(tmp_path: Path) -> None:
    path = config(tmp_path, '[devices.spotify]\ndriver = "spotify"\n')
    result = CliRunner().invoke(app, ["devices", "login", "radio", "--config", str(path)])
    assert result.exit_code == 2
    assert "unknown device 'radio'; devices in this world: spotify" in result.output


def test_a_driver_without_a_login_says_so(tmp_path: Path) -> None:
    pytest.importorskip("rosaos_tapo")  # another driver; this package may be installed alone
    path = config(tmp_path, '[devices.lamp]\ndriver = "tapo"\n')
    result = CliRunner().invoke(app, ["devices", "login", "lamp", "--config", str(path)])
    assert result.exit_code == 0
    assert "driver 'tapo' needs no login" in result.output
