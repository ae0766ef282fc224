"""The player's MCP tools, driven through FastMCP's in-memory client on the simulator."""

from __future__ import annotations

from typing import Any

STATE_KEYS = {"is_playing", "volume", "track", "artist", "shuffle", "repeat"}
TOOLS = {
    "get_state",
    "play",
    "pause",
    "resume",
    "next_track",
    "previous_track",
    "set_volume",
    "change_volume",
    "set_shuffle",
    "set_repeat",
    "queue",
    "search",
}


# The tool list


async def test_server_offers_exactly_the_player_tools(open_player: Any) -> None:
    async with open_player() as player:
        tools = await player.client.list_tools()
    assert {tool.name for tool in tools} == TOOLS


async def test_every_tool_sets_read_only_destructive_and_idempotent_hints(open_player: Any) -> None:
    async with open_player() as player:
        tools = await player.client.list_tools()
    for tool in tools:
        hints = tool.annotations
        assert hints is not None, tool.name
        assert hints.read_only_hint is not None, tool.name
        assert hints.destructive_hint is False, tool.name
        assert hints.idempotent_hint is not None, tool.name


async def test_only_get_state_and_search_are_read_only(open_player: Any) -> None:
    async with open_player() as player:
        tools = await player.client.list_tools()
    assert {t.name for t in tools if t.annotations and t.annotations.read_only_hint} == {
        "get_state",
        "search",
    }


async def test_relative_and_restarting_tools_are_not_idempotent(open_player: Any) -> None:
    async with open_player() as player:
        tools = await player.client.list_tools()
    repeated = {t.name for t in tools if t.annotations and not t.annotations.idempotent_hint}
    assert repeated == {"play", "next_track", "previous_track", "change_volume", "queue"}


# get_state


async def test_get_state_returns_exactly_the_bench_keys(open_player: Any) -> None:
    async with open_player() as player:
        assert set(await player.state()) == STATE_KEYS


async def test_bench_initial_state_is_echoed(open_player: Any, home_catalog: Any) -> None:
    bench = {"is_playing": True, "volume": 40, "track": "So What", "shuffle": False, "repeat": "off"}
    async with open_player(**bench, catalog=home_catalog) as player:
        state = await player.state()
    assert state == {**bench, "artist": "Miles Davis"}


# The bench's music tasks, tool by tool


async def test_play_a_title(open_player: Any, home_catalog: Any) -> None:
    async with open_player(catalog=home_catalog) as player:
        report = await player.call("play", query="Clair de Lune")
    assert report["message"] == "Playing Clair de Lune by Claude Debussy."
    assert (report["state"]["is_playing"], report["state"]["track"]) == (True, "Clair de Lune")


async def test_play_some_jazz_plays_a_jazz_track(open_player: Any, home_catalog: Any) -> None:
    async with open_player(catalog=home_catalog) as player:
        report = await player.call("play", query="some jazz")
    assert report["state"]["track"] in {"So What", "Take Five"}
    assert report["state"]["is_playing"] is True


async def test_play_is_accent_insensitive(open_player: Any, home_catalog: Any) -> None:
    async with open_player(catalog=home_catalog) as player:
        report = await player.call("play", query="gymnopedie")
    assert report["state"]["track"] == "Gymnopédie No. 1"


async def test_play_with_a_kind_limits_the_search(open_player: Any) -> None:
    async with open_player() as player:
        report = await player.call("play", query="Thriller", kind="album")
    assert report["message"].startswith("Playing the album Thriller")


async def test_pause_stops_playback_and_keeps_the_track(open_player: Any, home_catalog: Any) -> None:
    async with open_player(is_playing=True, track="So What", catalog=home_catalog) as player:
        report = await player.call("pause")
    assert (report["state"]["is_playing"], report["state"]["track"]) == (False, "So What")


async def test_set_volume(open_player: Any) -> None:
    async with open_player(volume=40) as player:
        report = await player.call("set_volume", volume=70)
    assert report["message"] == "Volume 40% → 70%."
    assert report["state"]["volume"] == 70


async def test_change_volume_turns_it_up_and_stays_within_bounds(open_player: Any) -> None:
    async with open_player(volume=90) as player:
        louder = await player.call("change_volume", delta=15)
        quieter = await player.call("change_volume", delta=-100)
    assert (louder["state"]["volume"], quieter["state"]["volume"]) == (100, 0)


async def test_next_track_changes_the_track_and_keeps_playing(open_player: Any, home_catalog: Any) -> None:
    async with open_player(is_playing=True, track="So What", catalog=home_catalog) as player:
        report = await player.call("next_track")
    assert report["state"]["track"] != "So What"
    assert report["state"]["is_playing"] is True


async def test_resume_and_previous_track(open_player: Any, home_catalog: Any) -> None:
    async with open_player(track="Take Five", catalog=home_catalog) as player:
        resumed = await player.call("resume")
        previous = await player.call("previous_track")
    assert resumed["state"]["is_playing"] is True
    assert previous["state"]["track"] == "So What"


async def test_shuffle_and_repeat(open_player: Any) -> None:
    async with open_player() as player:
        await player.call("set_shuffle", shuffle=True)
        report = await player.call("set_repeat", repeat="track")
    assert (report["state"]["shuffle"], report["state"]["repeat"]) == (True, "track")


async def test_queue_reports_the_queued_track(open_player: Any, home_catalog: Any) -> None:
    async with open_player(is_playing=True, track="So What", catalog=home_catalog) as player:
        report = await player.call("queue", query="Bohemian Rhapsody")
    assert report["message"].startswith("Queued Bohemian Rhapsody by Queen")
    assert report["state"]["track"] == "So What"


async def test_search_lists_matches_without_playing(open_player: Any, home_catalog: Any) -> None:
    async with open_player(catalog=home_catalog) as player:
        results = await player.call("search", query="jazz", limit=3)
        state = await player.state()
    assert results["hits"][0] == {"kind": "genre", "name": "jazz", "artist": None, "album": None}
    assert state["is_playing"] is False


# Refusals


async def test_a_query_that_finds_nothing_is_a_tool_error_that_changes_nothing(
    open_player: Any, home_catalog: Any
) -> None:
    async with open_player(is_playing=True, track="So What", catalog=home_catalog) as player:
        before = await player.state()
        error = await player.error("play", query="polka")
        after = await player.state()
    assert 'found nothing matching "polka"' in error
    assert "a genre (classical, jazz, rock)" in error
    assert after == before


async def test_volume_out_of_range_is_refused_naming_the_argument(open_player: Any) -> None:
    async with open_player() as player:
        error = await player.error("set_volume", volume=101)
    assert "volume" in error


async def test_unknown_repeat_mode_is_refused(open_player: Any) -> None:
    async with open_player() as player:
        error = await player.error("set_repeat", repeat="forever")
    assert "repeat" in error


async def test_search_limit_is_bounded(open_player: Any) -> None:
    async with open_player() as player:
        error = await player.error("search", query="jazz", limit=50)
    assert "limit" in error
