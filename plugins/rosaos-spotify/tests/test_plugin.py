"""The driver as rosaOS sees it: entry point, spec, settings, demo instance, safe stop, login hook."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from pydantic import ValidationError

from rosaos.drivers import DeviceContext, DeviceError
from rosaos.plugins import load_drivers
from rosaos_spotify.plugin import SPEC, pause_music, real_backend
from rosaos_spotify.settings import SpotifySettings
from rosaos_spotify.web_api import WebApiBackend


def real_context(tmp_path: Path, **settings: Any) -> DeviceContext:
    return DeviceContext(
        instance="spotify",
        description="Music on the living room speaker",
        settings=SpotifySettings(**settings),
        backend="real",
        data_dir=tmp_path,
    )


def test_entry_point_registers_the_spotify_driver() -> None:
    registry = load_drivers(allow={"spotify"})
    assert registry.broken == []
    info = registry.get("spotify")
    assert (info.package, info.spec.name, info.spec.implemented) == ("rosaos-spotify", "spotify", True)


def test_a_player_is_held_by_one_process_at_a_time() -> None:
    assert SPEC.concurrency == "exclusive"


def test_demo_world_has_the_living_room_music() -> None:
    demo = SPEC.demo_instances()
    assert list(demo) == ["spotify"]
    assert demo["spotify"].description == "Music on the living room speaker"


def test_settings_default_to_the_loopback_redirect_uri() -> None:
    assert SpotifySettings().redirect_uri == "http://127.0.0.1:8888/callback"


def test_settings_reject_unknown_keys_and_bad_markets() -> None:
    with pytest.raises(ValidationError, match="clientid"):
        SpotifySettings.model_validate({"clientid": "abc"})
    with pytest.raises(ValidationError, match="market"):
        SpotifySettings(market="germany")


def test_real_backend_without_client_id_says_how_to_get_one(tmp_path: Path) -> None:
    with pytest.raises(DeviceError, match=r"needs client_id.*developer\.spotify\.com/dashboard"):
        real_backend(real_context(tmp_path))


async def test_real_backend_without_a_login_refuses_to_start(tmp_path: Path) -> None:
    backend = real_backend(real_context(tmp_path, client_id="abc123", device="Living Room"))
    assert isinstance(backend, WebApiBackend)
    assert backend.device == "Living Room"
    with pytest.raises(DeviceError, match="rosaos devices login spotify"):
        await backend.start()


def test_login_hook_is_declared_and_explains_a_missing_client_id(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert SPEC.login is not None
    assert SPEC.login(real_context(tmp_path)) == 2
    assert "has no client_id" in capsys.readouterr().out


async def test_safe_stop_pauses_the_music(open_player: Any, home_catalog: Any) -> None:
    async with open_player(is_playing=True, track="So What", catalog=home_catalog) as player:
        await pause_music(player.backend)
        state = await player.state()
    assert (state["is_playing"], state["track"]) == (False, "So What")


async def test_safe_stop_with_nothing_playing_is_fine(open_player: Any) -> None:
    async with open_player() as player:
        await pause_music(player.backend)
        assert (await player.state())["is_playing"] is False
