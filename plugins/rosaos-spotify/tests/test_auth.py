"""The token file (owner-only, atomic) and the PKCE manager that never prompts."""

from __future__ import annotations

import stat
from pathlib import Path

import pytest

from rosaos_spotify.auth import NotLoggedIn, TokenCache, auth_manager, token_path


def mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


def test_tokens_live_in_the_data_dir_per_instance(tmp_path: Path) -> None:
    assert token_path(tmp_path, "kitchen_music") == tmp_path / "drivers" / "spotify" / "kitchen_music.json"


def test_saved_token_is_readable_by_its_owner_only(tmp_path: Path) -> None:
    cache = TokenCache(token_path(tmp_path, "spotify"))
    cache.save_token_to_cache({"access_token": "a", "refresh_token": "r"})
    assert mode(cache.path) == 0o600
    assert mode(cache.path.parent) == 0o700


def test_saving_replaces_the_file_and_leaves_no_temporary_behind(tmp_path: Path) -> None:
    cache = TokenCache(token_path(tmp_path, "spotify"))
    cache.save_token_to_cache({"access_token": "old", "refresh_token": "r"})
    cache.save_token_to_cache({"access_token": "new", "refresh_token": "r"})
    assert cache.get_cached_token() == {"access_token": "new", "refresh_token": "r"}
    assert [p.name for p in cache.path.parent.iterdir()] == ["spotify.json"]
    assert mode(cache.path) == 0o600


def test_a_loosened_file_is_tightened_on_the_next_save(tmp_path: Path) -> None:
    cache = TokenCache(token_path(tmp_path, "spotify"))
    cache.save_token_to_cache({"refresh_token": "r"})
    cache.path.chmod(0o644)
    cache.save_token_to_cache({"refresh_token": "r2"})
    assert mode(cache.path) == 0o600


@pytest.mark.parametrize("content", [None, "not json", "[1, 2]"])
def test_missing_or_unreadable_file_means_no_login(tmp_path: Path, content: str | None) -> None:
    cache = TokenCache(token_path(tmp_path, "spotify"))
    if content is not None:
        cache.path.parent.mkdir(parents=True)
        cache.path.write_text(content)
    assert cache.get_cached_token() is None
    assert cache.has_login() is False


def test_without_a_login_the_manager_raises_instead_of_prompting(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def no_prompt(*args: object) -> str:
        raise AssertionError("a device server must never wait for input")

    monkeypatch.setattr("builtins.input", no_prompt)
    monkeypatch.setattr("webbrowser.open", no_prompt)
    manager = auth_manager("abc123", "http://127.0.0.1:8888/callback", TokenCache(tmp_path / "t.json"), 5)
    with pytest.raises(NotLoggedIn):
        manager.get_access_token()


def test_a_login_missing_a_scope_counts_as_logged_out(tmp_path: Path) -> None:
    cache = TokenCache(tmp_path / "t.json")
    cache.save_token_to_cache(
        {"access_token": "a", "refresh_token": "r", "expires_at": 2**40, "scope": "user-read-private"}
    )
    manager = auth_manager("abc123", "http://127.0.0.1:8888/callback", cache, 5)
    with pytest.raises(NotLoggedIn):
        manager.get_access_token()
