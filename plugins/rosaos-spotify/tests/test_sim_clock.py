"""The simulator's clock (``sim.track_seconds``): music that runs out is ``playback_ended``."""

from __future__ import annotations

import asyncio
import random
from pathlib import Path
from typing import Any

from rosaos.drivers import DeviceContext, NoticeBoard
from rosaos_spotify.plugin import SPEC, sim_backend
from rosaos_spotify.settings import SpotifySettings
from rosaos_spotify.simulator import SimPlayer, SimSettings

from .spotify_catalogs import ALBUMS


def clocked(**sim: Any) -> SimPlayer:
    """A player whose tracks last 10 s, on :data:`ALBUMS`."""
    sim.setdefault("catalog", ALBUMS)
    return SimPlayer(SimSettings.from_sim("spotify", {"track_seconds": 10, **sim}), random.Random(0))


def test_without_track_seconds_time_stands_still() -> None:
    p = SimPlayer(SimSettings.from_sim("spotify", {"catalog": ALBUMS}), random.Random(0))
    p.play("Kind of Blue")
    assert p.tick(1e6) is False
    assert (p.state().track, p.state().is_playing) == ("So What", True)


def test_tracks_follow_each_other_and_the_album_ends_without_autoplay() -> None:
    p = clocked(autoplay=False)
    p.play("Kind of Blue")
    assert p.tick(9) is False and p.state().track == "So What"
    assert p.tick(2) is False and p.state().track == "Freddie Freeloader"
    assert p.tick(10) is False and p.state().track == "Blue in Green"
    assert p.tick(10) is True
    assert (p.state().track, p.state().is_playing) == ("Blue in Green", False)
    assert p.tick(100) is False  # stopped music stays stopped


def test_autoplay_keeps_going_after_the_album() -> None:
    p = clocked()
    p.play("Kind of Blue")
    assert p.tick(30) is False
    assert p.state().is_playing and p.state().track == "Take Five"


def test_queue_and_repeat_keep_the_music_going() -> None:
    p = clocked(autoplay=False)
    p.play("Clair de Lune")
    p.queue("Take Five")
    assert p.tick(10) is False and p.state().track == "Take Five"
    p.set_repeat("track")
    assert p.tick(50) is False and p.state().track == "Take Five"
    p.set_repeat("off")
    assert p.tick(10) is True


def test_a_paused_track_does_not_run_out_and_a_skip_restarts_the_clock() -> None:
    p = clocked(autoplay=False)
    p.play("Kind of Blue")
    p.tick(8)
    p.pause()
    assert p.tick(100) is False and p.state().track == "So What"
    p.resume()
    p.next_track()
    assert p.tick(9) is False and p.state().track == "Freddie Freeloader"


def test_skipping_past_the_last_track_without_autoplay_stops() -> None:
    p = clocked(autoplay=False)
    p.play("Clair de Lune")
    assert "last track" in p.next_track()
    assert p.state().is_playing is False


async def test_the_running_simulator_posts_playback_ended_once(tmp_path: Path) -> None:
    board = NoticeBoard("spotify", "spotify", SPEC.notices)
    sim = {"catalog": ALBUMS, "track_seconds": 0.2, "autoplay": False}
    ctx = DeviceContext("spotify", "Speaker", SpotifySettings(), "sim", sim, tmp_path, notices=board)
    backend = sim_backend(ctx)
    await backend.start()
    try:
        await backend.play("Clair de Lune")
        for _ in range(100):
            if board.after(0).notices:
                break
            await asyncio.sleep(0.05)
        await asyncio.sleep(0.3)  # a second notice would come within a few ticks
        state = await backend.state()
    finally:
        await backend.close()
    notices = board.after(0).notices
    assert [n.name for n in notices] == ["playback_ended"]
    assert notices[0].data == {"track": "Clair de Lune", "artist": "Claude Debussy"}
    assert notices[0].importance == "info"
    assert notices[0].message == "playback ended after Clair de Lune by Claude Debussy"
    assert state.is_playing is False
