"""The simulated player's rules: contexts, the queue, shuffle, repeat, autoplay, the initial state."""

from __future__ import annotations

import random
from typing import Any

import pytest

from rosaos.drivers import DeviceError
from rosaos_spotify.catalog import DEFAULT_CATALOG
from rosaos_spotify.simulator import SimPlayer, SimSettings

from .spotify_catalogs import ALBUMS


def player(**sim: Any) -> SimPlayer:
    sim.setdefault("catalog", ALBUMS)
    return SimPlayer(SimSettings.from_sim("spotify", sim), random.Random(0))


def titles(p: SimPlayer, skips: int) -> list[str | None]:
    """The current track, then the track after each of ``skips`` next_track calls."""
    seen = [p.state().track]
    for _ in range(skips):
        p.next_track()
        seen.append(p.state().track)
    return seen


# Initial state


def test_defaults_are_a_stopped_player_on_the_built_in_catalog() -> None:
    p = SimPlayer(SimSettings.from_sim("spotify", {}), random.Random(0))
    assert p.state().model_dump() == {
        "is_playing": False,
        "volume": 50,
        "track": None,
        "artist": None,
        "shuffle": False,
        "repeat": "off",
    }
    assert p.catalog == DEFAULT_CATALOG


def test_initial_track_takes_its_artist_from_the_catalog() -> None:
    p = player(is_playing=True, track="So What")
    assert (p.state().track, p.state().artist, p.state().is_playing) == ("So What", "Miles Davis", True)


def test_unknown_sim_key_is_refused_naming_the_allowed_ones() -> None:
    with pytest.raises(DeviceError, match=r"unknown key\(s\) 'colour'.*is_playing, volume"):
        SimSettings.from_sim("spotify", {"colour": "red"})


def test_out_of_range_volume_is_refused() -> None:
    with pytest.raises(DeviceError, match=r"devices.spotify.sim: volume"):
        SimSettings.from_sim("spotify", {"volume": 140})


def test_initial_track_missing_from_the_catalog_is_refused_with_choices() -> None:
    with pytest.raises(DeviceError, match=r"'Yesterday' is not in the catalog.*So What by Miles Davis"):
        player(track="Yesterday")


def test_playing_without_a_track_is_refused() -> None:
    with pytest.raises(DeviceError, match="need a track"):
        SimSettings.from_sim("spotify", {"is_playing": True})


def test_catalog_entries_must_have_a_title_and_artist() -> None:
    with pytest.raises(DeviceError, match=r"catalog\.0\.artist"):
        SimSettings.from_sim("spotify", {"catalog": [{"track": "Untitled"}]})


# Contexts


def test_a_track_plays_within_its_album() -> None:
    p = player()
    p.play("Freddie Freeloader")
    assert titles(p, 1) == ["Freddie Freeloader", "Blue in Green"]


def test_an_artist_plays_all_their_tracks_in_catalog_order() -> None:
    p = player()
    assert p.play("Miles Davis").startswith("Playing songs by Miles Davis")
    assert titles(p, 2) == ["So What", "Freddie Freeloader", "Blue in Green"]


def test_a_genre_plays_its_tracks() -> None:
    p = player()
    p.play("some jazz")
    assert titles(p, 3) == ["So What", "Freddie Freeloader", "Blue in Green", "Take Five"]


def test_previous_goes_back_within_the_context() -> None:
    p = player()
    p.play("Blue in Green")
    p.previous_track()
    assert p.state().track == "Freddie Freeloader"


def test_previous_on_the_first_track_restarts_it() -> None:
    p = player()
    p.play("So What")
    assert "from the beginning" in p.previous_track()
    assert p.state().track == "So What"


def test_autoplay_continues_with_the_same_genre_after_the_context() -> None:
    p = player()
    p.play("Take Five")  # alone on its album
    assert "autoplay" in p.next_track()
    assert p.state().track == "So What"  # jazz before classical


def test_repeat_context_starts_the_context_over() -> None:
    p = player(repeat="context")
    p.play("the album Kind of Blue")
    assert titles(p, 3) == ["So What", "Freddie Freeloader", "Blue in Green", "So What"]


def test_repeat_context_makes_previous_wrap_to_the_last_track() -> None:
    p = player(repeat="context")
    p.play("the album Kind of Blue")
    p.previous_track()
    assert p.state().track == "Blue in Green"


def test_skipping_starts_playback_like_spotify() -> None:
    p = player(is_playing=False, track="So What")
    p.next_track()
    assert p.state().is_playing is True


def test_next_with_nothing_loaded_is_refused() -> None:
    with pytest.raises(DeviceError, match=r"nothing is loaded.*use play"):
        player().next_track()


def test_a_one_track_catalog_replays_its_track() -> None:
    p = player(catalog=ALBUMS[:1], track="So What")
    assert "nothing else" in p.next_track()
    assert p.state().track == "So What"


# Queue


def test_queued_track_plays_next_then_the_context_resumes() -> None:
    p = player()
    p.play("So What")
    p.queue("Clair de Lune")
    assert titles(p, 2) == ["So What", "Clair de Lune", "Freddie Freeloader"]


def test_previous_after_a_queued_track_returns_to_the_context() -> None:
    p = player()
    p.play("So What")
    p.queue("Clair de Lune")
    p.next_track()
    p.previous_track()
    assert p.state().track == "So What"


def test_queueing_does_not_interrupt_the_current_track() -> None:
    p = player(is_playing=True, track="So What")
    p.queue("Take Five")
    assert (p.state().track, p.state().is_playing) == ("So What", True)


# Shuffle


def test_shuffle_plays_every_track_of_the_context_once() -> None:
    p = player(shuffle=True)
    p.play("Miles Davis")
    assert sorted(map(str, titles(p, 2))) == ["Blue in Green", "Freddie Freeloader", "So What"]


def test_turning_shuffle_on_keeps_the_current_track() -> None:
    p = player()
    p.play("Blue in Green")
    p.set_shuffle(True)
    assert p.state().track == "Blue in Green"


def test_turning_shuffle_off_returns_to_album_order() -> None:
    p = player(shuffle=True)
    p.play("Freddie Freeloader")
    p.set_shuffle(False)
    assert titles(p, 1) == ["Freddie Freeloader", "Blue in Green"]


def test_a_shuffled_run_repeats_with_the_same_seed() -> None:
    first, second = player(shuffle=True), player(shuffle=True)
    for p in (first, second):
        p.play("some jazz")
    assert titles(first, 3) == titles(second, 3)


# Pause, resume, volume


def test_pause_then_resume_keeps_the_track() -> None:
    p = player(is_playing=True, track="Take Five")
    p.pause()
    assert p.state().is_playing is False
    p.resume()
    assert (p.state().track, p.state().is_playing) == ("Take Five", True)


def test_resume_with_nothing_loaded_starts_the_catalog() -> None:
    p = player()
    assert "Nothing was loaded" in p.resume()
    assert (p.state().track, p.state().is_playing) == ("So What", True)


def test_play_anything_plays_the_whole_catalog() -> None:
    p = player()
    assert "whole catalog" in p.play("some music")
    assert p.state().is_playing is True


def test_nothing_found_changes_nothing() -> None:
    p = player(is_playing=True, track="So What", volume=30)
    before = p.state()
    with pytest.raises(DeviceError, match=r'found nothing matching "polka".*Try a title'):
        p.play("polka")
    assert p.state() == before
