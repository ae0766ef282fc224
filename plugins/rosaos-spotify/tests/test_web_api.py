"""The real backend against recorded Spotify Web API answers (the ``responses`` library).

Nothing leaves the machine: ``responses`` answers every request spotipy makes, and fails the
test on any request it was not told about. The JSON bodies in ``fixtures/`` have the shape of
Spotify's answers (Web API reference, 2025); the error bodies are the ones Spotify sends.
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import responses
from fastmcp import Client
from responses import matchers

from rosaos.drivers import DeviceContext, DeviceError, NoticeBoard
from rosaos_spotify.auth import SCOPES, TokenCache, token_path
from rosaos_spotify.plugin import SPEC
from rosaos_spotify.server import build_server
from rosaos_spotify.settings import SpotifySettings
from rosaos_spotify.web_api import WebApiBackend, build_web_backend

API = "https://api.spotify.com/v1"
TOKEN_URL = "https://accounts.spotify.com/api/token"
FIXTURES = Path(__file__).parent / "fixtures"
PLAYER = f"{API}/me/player"
CLAIR_ALBUM = "spotify:album:2Ta7Em5y0hXw9PCvBvSdDJ"
CLAIR_TRACK = "spotify:track:6kf8s2nY6kJ3K8wOCZcXdH"
SPEAKER_ID = "5fbb3ba6aa454b5534c4ba43a8c7e8e45a63ad0e"


def fixture(name: str) -> Any:
    return json.loads((FIXTURES / f"{name}.json").read_text(encoding="utf-8"))


def player_error(status: int, message: str, reason: str) -> dict[str, Any]:
    """A refused player command, as Spotify words it."""
    return {"error": {"status": status, "message": f"Player command failed: {message}", "reason": reason}}


def playing(track: str = "Clair de Lune", **changes: Any) -> dict[str, Any]:
    """``GET /me/player`` while ``track`` plays, with top-level fields changed."""
    body = fixture("player_clair_de_lune")
    body["item"]["name"] = track
    if "volume" in changes:
        body["device"]["volume_percent"] = changes.pop("volume")
    return {**body, **changes}


def save_login(data_dir: Path, *, expires_in: float = 3600) -> TokenCache:
    cache = TokenCache(token_path(data_dir, "spotify"))
    cache.save_token_to_cache(
        {
            "access_token": "BQD-access",
            "token_type": "Bearer",
            "expires_in": 3600,
            "expires_at": int(time.time() + expires_in),
            "refresh_token": "AQB-refresh",
            "scope": " ".join(SCOPES),
        }
    )
    return cache


def backend_for(data_dir: Path, **settings: Any) -> WebApiBackend:
    backend = build_web_backend("spotify", SpotifySettings(client_id="abc123", **settings), data_dir)
    backend.settle_delay = 0  # the recorded player answers at once
    return backend


@pytest.fixture
def api() -> Iterator[responses.RequestsMock]:
    """Intercepts every HTTP request; an unregistered one fails the test."""
    with responses.RequestsMock(assert_all_requests_are_fired=False) as mock:
        yield mock


@pytest.fixture
def spotify(tmp_path: Path) -> WebApiBackend:
    """A logged-in real backend using the active device."""
    save_login(tmp_path)
    return backend_for(tmp_path)


def sent_json(call: Any) -> Any:
    return json.loads(call.request.body) if call.request.body else None


# Playing


async def test_play_a_title_searches_then_plays_it_within_its_album(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    search = api.get(
        f"{API}/search",
        json=fixture("search_clair_de_lune"),
        match=[
            matchers.query_param_matcher(
                {
                    "q": "Clair de Lune",
                    "type": "track,artist,album",
                    "limit": "5",
                    "offset": "0",
                    "market": "from_token",
                }
            )
        ],
    )
    play = api.put(f"{PLAYER}/play", status=204)
    api.get(PLAYER, json=playing())
    report = await spotify.play("Clair de Lune")
    assert search.call_count == 1
    assert sent_json(play.calls[0]) == {"context_uri": CLAIR_ALBUM, "offset": {"uri": CLAIR_TRACK}}
    assert report.message == "Playing Clair de Lune by Claude Debussy."
    assert report.state.model_dump() == {
        "is_playing": True,
        "volume": 40,
        "track": "Clair de Lune",
        "artist": "Claude Debussy",
        "shuffle": False,
        "repeat": "off",
    }


async def test_play_some_jazz_plays_tracks_of_the_genre(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    api.get(
        f"{API}/search",
        json=fixture("search_genre_jazz"),
        match=[
            matchers.query_param_matcher(
                {"q": 'genre:"jazz"', "type": "track", "limit": "20"}, strict_match=False
            )
        ],
    )
    play = api.put(f"{PLAYER}/play", status=204)
    api.get(PLAYER, json=playing("So What"))
    report = await spotify.play("some jazz")
    assert sent_json(play.calls[0])["uris"][:2] == [
        "spotify:track:4vLYewWIvqHfKtJDk8c8tq",
        "spotify:track:1YQWosTIljIvxAgHWTp7KP",
    ]
    assert report.message.startswith("Playing some jazz: So What by Miles Davis")


async def test_play_on_the_configured_device_by_name(api: responses.RequestsMock, tmp_path: Path) -> None:
    save_login(tmp_path)
    backend = backend_for(tmp_path, device="living room")
    api.get(f"{API}/search", json=fixture("search_clair_de_lune"))
    api.get(f"{PLAYER}/devices", json=fixture("devices"))
    play = api.put(f"{PLAYER}/play", status=204)
    api.get(PLAYER, json=playing())
    await backend.play("Clair de Lune")
    assert play.calls[0].request.url.endswith(f"device_id={SPEAKER_ID}")


async def test_configured_device_offline_names_the_online_ones(
    api: responses.RequestsMock, tmp_path: Path
) -> None:
    save_login(tmp_path)
    backend = backend_for(tmp_path, device="Kitchen")
    api.get(f"{PLAYER}/devices", json=fixture("devices"))
    with pytest.raises(
        DeviceError, match=r'no Spotify device called "Kitchen".*"Living Room", "Maria\'s iPhone"'
    ):
        await backend.pause()


async def test_nothing_found_is_an_error_and_nothing_is_played(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    empty = {kind: {"items": [], "total": 0} for kind in ("tracks", "artists", "albums")}
    api.get(f"{API}/search", json=empty)
    with pytest.raises(DeviceError, match=r'found nothing for "zzkx".*genre such as jazz'):
        await spotify.play("zzkx")
    assert [call.request.method for call in api.calls] == ["GET"]


# Pause, volume, skip


async def test_pause(api: responses.RequestsMock, spotify: WebApiBackend) -> None:
    pause = api.put(f"{PLAYER}/pause", status=204)
    api.get(PLAYER, json=playing(is_playing=False))
    report = await spotify.pause()
    assert pause.call_count == 1
    assert (report.message, report.state.is_playing) == ("Paused.", False)


async def test_pause_with_no_active_device_is_not_an_error(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    # An emergency stop pauses every player; one that plays nothing must not fail it.
    api.put(
        f"{PLAYER}/pause", status=404, json=player_error(404, "No active device found", "NO_ACTIVE_DEVICE")
    )
    api.get(PLAYER, status=204)
    api.get(f"{PLAYER}/devices", json={"devices": []})
    report = await spotify.pause()
    assert (report.message, report.state.is_playing, report.state.track) == (
        "Nothing is playing.",
        False,
        None,
    )


async def test_set_volume(api: responses.RequestsMock, spotify: WebApiBackend) -> None:
    api.get(PLAYER, json=playing(volume=40))
    volume = api.put(f"{PLAYER}/volume", status=204)
    report = await spotify.set_volume(70)
    assert "volume_percent=70" in volume.calls[0].request.url
    assert (report.message, report.state.volume) == ("Volume 40% → 70%.", 70)


async def test_change_volume_adds_to_the_current_volume(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    api.get(PLAYER, json=playing(volume=40))
    volume = api.put(f"{PLAYER}/volume", status=204)
    await spotify.change_volume(15)
    assert "volume_percent=55" in volume.calls[0].request.url


async def test_next_track_waits_for_the_new_track(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    api.get(PLAYER, json=playing("Clair de Lune"))
    api.post(f"{PLAYER}/next", status=204)
    api.get(PLAYER, json=playing("Clair de Lune"))  # Spotify has not switched yet
    api.get(PLAYER, json=playing("Passepied"))
    report = await spotify.next_track()
    assert report.state.track == "Passepied"


async def test_state_with_nothing_active_reads_the_device_volume(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    api.get(PLAYER, status=204)
    api.get(f"{PLAYER}/devices", json=fixture("devices"))
    state = await spotify.state()
    assert state.model_dump() == {
        "is_playing": False, "volume": 35, "track": None, "artist": None, "shuffle": False, "repeat": "off",
    }  # fmt: skip


# The errors Spotify users hit


async def test_no_active_device_says_to_open_spotify_or_set_a_device(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    api.put(
        f"{PLAYER}/play", status=404, json=player_error(404, "No active device found", "NO_ACTIVE_DEVICE")
    )
    api.get(f"{PLAYER}/devices", json={"devices": []})
    with pytest.raises(DeviceError) as error:
        await spotify.resume()
    assert "open Spotify on a phone, computer or speaker and play something once" in str(error.value)
    assert 'set device = "<device name>" in [devices.spotify]' in str(error.value)


async def test_no_active_device_but_an_idle_one_plays_there(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    play = api.put(
        f"{PLAYER}/play", status=404, json=player_error(404, "No active device found", "NO_ACTIVE_DEVICE")
    )
    api.get(f"{PLAYER}/devices", json=fixture("devices"))
    retry = api.put(f"{PLAYER}/play", status=204)
    api.get(PLAYER, json=playing())
    report = await spotify.resume()
    assert play.call_count + retry.call_count == 2
    assert api.calls[-2].request.url.endswith(f"device_id={SPEAKER_ID}")
    assert report.state.is_playing is True


async def test_premium_required_says_so(api: responses.RequestsMock, spotify: WebApiBackend) -> None:
    api.put(f"{PLAYER}/pause", status=403, json=player_error(403, "Premium required", "PREMIUM_REQUIRED"))
    with pytest.raises(DeviceError, match=r"needs Spotify Premium.*rosaos devices login spotify"):
        await spotify.pause()


async def test_revoked_login_says_to_log_in_again(api: responses.RequestsMock, tmp_path: Path) -> None:
    save_login(tmp_path, expires_in=-60)  # spotipy refreshes first, and Spotify refuses
    backend = backend_for(tmp_path)
    api.post(
        TOKEN_URL, status=400, json={"error": "invalid_grant", "error_description": "Refresh token revoked"}
    )
    with pytest.raises(DeviceError, match=r"expired or was revoked: run `rosaos devices login spotify`"):
        await backend.state()


async def test_expired_access_token_is_refreshed_once_and_the_call_retried(
    api: responses.RequestsMock, tmp_path: Path
) -> None:
    cache = save_login(tmp_path)
    backend = backend_for(tmp_path)
    expired = {"error": {"status": 401, "message": "The access token expired"}}
    api.get(PLAYER, status=401, json=expired)
    refresh = api.post(
        TOKEN_URL,
        json={
            "access_token": "BQD-new",
            "token_type": "Bearer",
            "expires_in": 3600,
            "scope": " ".join(SCOPES),
        },
    )
    api.get(PLAYER, json=playing())
    state = await backend.state()
    assert state.track == "Clair de Lune"
    assert "grant_type=refresh_token" in str(refresh.calls[0].request.body)
    saved = cache.get_cached_token() or {}
    assert (saved["access_token"], saved["refresh_token"]) == ("BQD-new", "AQB-refresh")


async def test_token_rejected_after_refresh_says_to_log_in(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    api.get(PLAYER, status=401, json={"error": {"status": 401, "message": "Invalid access token"}})
    api.post(
        TOKEN_URL,
        json={
            "access_token": "BQD-new",
            "token_type": "Bearer",
            "expires_in": 3600,
            "scope": " ".join(SCOPES),
        },
    )
    with pytest.raises(DeviceError, match=r"rejected the access token.*rosaos devices login spotify"):
        await spotify.state()


async def test_rate_limit_says_when_to_retry_and_does_not_wait(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    limited = api.get(
        PLAYER,
        status=429,
        headers={"Retry-After": "30"},
        json={"error": {"status": 429, "message": "API rate limit exceeded"}},
    )
    with pytest.raises(DeviceError, match="rate-limiting requests; try again in 30 s"):
        await spotify.state()
    assert limited.call_count == 1


async def test_start_without_a_login_says_how_to_log_in(tmp_path: Path) -> None:
    with pytest.raises(DeviceError, match=r"not logged in to Spotify: run `rosaos devices login spotify`"):
        await backend_for(tmp_path).start()


async def test_tool_error_text_carries_the_fix(api: responses.RequestsMock, spotify: WebApiBackend) -> None:
    """What the model reads when a tool fails: the fix-it message, no traceback."""
    api.put(f"{PLAYER}/pause", status=403, json=player_error(403, "Premium required", "PREMIUM_REQUIRED"))
    ctx_server = build_server(_context(), spotify)
    async with Client(ctx_server) as client:
        result = await client.call_tool("pause", {}, raise_on_error=False)
    text = " ".join(getattr(block, "text", "") for block in result.content)
    assert result.is_error
    assert "Premium" in text and "Traceback" not in text


def _context() -> Any:
    from rosaos.drivers import DeviceContext

    return DeviceContext(instance="spotify", description="Music", settings=SpotifySettings(), backend="real")


# Retries


async def test_a_server_error_on_a_read_is_retried(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    flaky = api.get(PLAYER, status=503)
    api.get(PLAYER, json=playing())
    assert (await spotify.state()).track == "Clair de Lune"
    assert flaky.call_count == 1


async def test_a_skip_is_not_retried_so_it_cannot_skip_twice(
    api: responses.RequestsMock, spotify: WebApiBackend
) -> None:
    api.get(PLAYER, json=playing())
    skip = api.post(f"{PLAYER}/next", status=502)
    with pytest.raises(DeviceError, match=r"Spotify is having trouble \(HTTP 502\)"):
        await spotify.next_track()
    assert skip.call_count == 1


# The watcher: the end of the music is a notice, a pause is not


def stopped(progress_ms: int) -> dict[str, Any]:
    return playing(is_playing=False, progress_ms=progress_ms)


def notices_of(backend: WebApiBackend, tmp_path: Path) -> NoticeBoard:
    """The board the backend's notices go to, as the hosting layer wires it."""
    board = NoticeBoard("spotify", "spotify", SPEC.notices)
    ctx = DeviceContext("spotify", "Speaker", SpotifySettings(), "real", {}, tmp_path, notices=board)
    backend.ending.notify = ctx.notify
    return board


async def watch_through(tmp_path: Path, answers: list[dict[str, Any] | None]) -> list[str]:
    """Let the watcher read ``answers`` in turn (None: nothing active); the notices it posted."""
    save_login(tmp_path)
    backend = backend_for(tmp_path)
    board = notices_of(backend, tmp_path)
    with responses.RequestsMock() as api:
        for answer in answers:
            api.get(PLAYER, status=204) if answer is None else api.get(PLAYER, json=answer)
        for _ in answers:
            await backend.watch()
    return [notice.name for notice in board.after(0).notices]


async def test_the_watcher_tells_the_end_of_the_music_from_a_pause(tmp_path: Path) -> None:
    assert await watch_through(tmp_path / "end", [playing(), stopped(0)]) == ["playback_ended"]
    assert await watch_through(tmp_path / "gone", [playing(), None]) == ["playback_ended"]
    assert await watch_through(tmp_path / "paused", [playing(), stopped(93_000)]) == []
    assert await watch_through(tmp_path / "idle", [stopped(0), stopped(0)]) == []


async def test_our_own_pause_is_not_the_music_ending(
    api: responses.RequestsMock, spotify: WebApiBackend, tmp_path: Path
) -> None:
    board = notices_of(spotify, tmp_path)
    api.get(PLAYER, json=playing())
    await spotify.watch()
    api.replace(responses.GET, PLAYER, json=stopped(0))  # paused right at the start of a track
    api.put(f"{PLAYER}/pause", status=204)
    await spotify.pause()
    await spotify.watch()
    assert board.after(0).notices == []


async def test_the_watcher_runs_from_start_to_close(tmp_path: Path) -> None:
    save_login(tmp_path)
    backend = backend_for(tmp_path, watch_seconds=0.05)
    board = notices_of(backend, tmp_path)
    with responses.RequestsMock(assert_all_requests_are_fired=False) as api:
        api.get(PLAYER, json=playing())
        api.get(PLAYER, json=stopped(0))
        await backend.start()
        try:
            for _ in range(100):
                if board.after(0).notices:
                    break
                await asyncio.sleep(0.05)
        finally:
            await backend.close()
    [notice] = board.after(0).notices
    assert notice.data == {"track": "Clair de Lune", "artist": "Claude Debussy"}
