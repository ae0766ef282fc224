"""Matching what people say against a catalog: filler words, accents, kinds, near misses."""

from __future__ import annotations

import pytest

from rosaos_spotify.catalog import DEFAULT_CATALOG, KNOWN_GENRES, clean_query, find, normalize


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("Clair de Lune", ("Clair de Lune", "any")),
        ("some jazz", ("jazz", "any")),
        ("a little bit of classical music", ("classical", "any")),
        ("songs by Miles Davis", ("Miles Davis", "artist")),
        ("something from Queen", ("Queen", "artist")),
        ("the album Abbey Road", ("Abbey Road", "album")),
        ("the song Take Five please", ("Take Five", "track")),
        ("The Beatles", ("The Beatles", "any")),
        ("some music", ("", "any")),
        ("anything", ("", "any")),
    ],
)
def test_clean_query_drops_filler_and_reads_the_kind(said: str, expected: tuple[str, str]) -> None:
    assert clean_query(said) == expected


def test_normalize_ignores_case_accents_punctuation_and_articles() -> None:
    assert normalize("Gymnopédie No. 1") == "gymnopedie no 1"
    assert normalize("The Beatles") == normalize("beatles")
    assert normalize("Bob Marley & The Wailers") == normalize("bob marley and the wailers")


def best(query: str) -> tuple[str, str]:
    cleaned, kind = clean_query(query)
    match = find(DEFAULT_CATALOG, cleaned, kind)[0]
    return match.kind, match.name


@pytest.mark.parametrize(
    ("query", "expected"),
    [
        ("Gymnopedie", ("track", "Gymnopédie No. 1")),
        ("fur elise", ("track", "Für Elise")),
        ("BOLERO", ("track", "Boléro")),
        ("some jazz", ("genre", "jazz")),
        ("Queen", ("artist", "Queen")),  # the band, not "Dancing Queen"
        ("beatles", ("artist", "The Beatles")),
        ("the album Abbey Road", ("album", "Abbey Road")),
        ("Thriller", ("track", "Thriller")),  # a song and its album share the name: the song
        ("Here Comes the Sun by The Beatles", ("track", "Here Comes the Sun")),
        ("So What Miles Davis", ("track", "So What")),
        ("Bohemian Rapsody", ("track", "Bohemian Rhapsody")),  # a near miss still finds it
    ],
)
def test_find_picks_the_best_match(query: str, expected: tuple[str, str]) -> None:
    assert best(query) == expected


def test_find_groups_an_artist_with_all_their_tracks_in_order() -> None:
    match = find(DEFAULT_CATALOG, "Miles Davis", "artist")[0]
    assert [entry.track for entry in match.tracks] == ["So What", "Blue in Green"]


def test_find_limited_to_a_kind_ignores_the_others() -> None:
    assert [m.kind for m in find(DEFAULT_CATALOG, "Thriller", "album")] == ["album"]


def test_find_returns_nothing_for_an_unknown_query() -> None:
    assert find(DEFAULT_CATALOG, "polka", "any") == []


def test_default_catalog_covers_the_main_genres_and_every_genre_is_known() -> None:
    genres = {entry.genre for entry in DEFAULT_CATALOG}
    assert {"jazz", "classical", "rock", "pop"} <= genres
    assert genres <= set(KNOWN_GENRES)
    assert len(DEFAULT_CATALOG) >= 30
