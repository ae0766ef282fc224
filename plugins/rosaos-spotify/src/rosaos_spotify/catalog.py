"""Music catalog entries, and how a spoken query is matched against them.

Both backends start from what people say ("some jazz", "songs by Queen", "the album Abbey Road",
"Gymnopedie"): :func:`clean_query` drops the filler words and reads the kind hint, and
:func:`normalize` makes matching case-, accent- and punctuation-insensitive. The simulator then
ranks its own catalog with :func:`find`; the real backend hands the cleaned query to Spotify's
search and uses :data:`KNOWN_GENRES` to route "jazz" to a genre search.
"""

from __future__ import annotations

import difflib
import re
import unicodedata
from dataclasses import dataclass
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

SearchKind = Literal["any", "track", "artist", "album", "genre"]
"""What a query names; ``any`` lets the backend decide."""
MatchKind = Literal["track", "artist", "album", "genre"]


class CatalogEntry(BaseModel):
    """One track of the simulator's catalog: the ``sim.catalog`` entries of a task file."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    track: str = Field(min_length=1, description="Track title.")
    artist: str = Field(min_length=1, description="Artist, as shown by Spotify.")
    album: str | None = Field(default=None, description="Album the track is on.")
    genre: str | None = Field(default=None, description="Genre, lowercase: jazz, classical, rock, pop...")


def _catalog(*rows: tuple[str, str, str, str]) -> tuple[CatalogEntry, ...]:
    return tuple(CatalogEntry(track=t, artist=a, album=al, genre=g) for t, a, al, g in rows)


DEFAULT_CATALOG = _catalog(
    ("So What", "Miles Davis", "Kind of Blue", "jazz"),
    ("Blue in Green", "Miles Davis", "Kind of Blue", "jazz"),
    ("Take Five", "The Dave Brubeck Quartet", "Time Out", "jazz"),
    ("Blue Rondo à la Turk", "The Dave Brubeck Quartet", "Time Out", "jazz"),
    ("My Favorite Things", "John Coltrane", "My Favorite Things", "jazz"),
    ("Giant Steps", "John Coltrane", "Giant Steps", "jazz"),
    ("Autumn Leaves", "Cannonball Adderley", "Somethin' Else", "jazz"),
    ("What a Wonderful World", "Louis Armstrong", "What a Wonderful World", "jazz"),
    ("Clair de Lune", "Claude Debussy", "Suite bergamasque", "classical"),
    ("Gymnopédie No. 1", "Erik Satie", "Gymnopédies", "classical"),
    ("Für Elise", "Ludwig van Beethoven", "Bagatelles", "classical"),
    ("Moonlight Sonata", "Ludwig van Beethoven", "Piano Sonatas", "classical"),
    ("Canon in D", "Johann Pachelbel", "Canon and Gigue", "classical"),
    ("Spring", "Antonio Vivaldi", "The Four Seasons", "classical"),
    ("Air on the G String", "Johann Sebastian Bach", "Orchestral Suite No. 3", "classical"),
    ("Boléro", "Maurice Ravel", "Boléro", "classical"),
    ("Here Comes the Sun", "The Beatles", "Abbey Road", "rock"),
    ("Come Together", "The Beatles", "Abbey Road", "rock"),
    ("Let It Be", "The Beatles", "Let It Be", "rock"),
    ("Bohemian Rhapsody", "Queen", "A Night at the Opera", "rock"),
    ("Another One Bites the Dust", "Queen", "The Game", "rock"),
    ("Stairway to Heaven", "Led Zeppelin", "Led Zeppelin IV", "rock"),
    ("Hotel California", "Eagles", "Hotel California", "rock"),
    ("Smells Like Teen Spirit", "Nirvana", "Nevermind", "rock"),
    ("Wish You Were Here", "Pink Floyd", "Wish You Were Here", "rock"),
    ("Billie Jean", "Michael Jackson", "Thriller", "pop"),
    ("Thriller", "Michael Jackson", "Thriller", "pop"),
    ("Dancing Queen", "ABBA", "Arrival", "pop"),
    ("Like a Prayer", "Madonna", "Like a Prayer", "pop"),
    ("Shake It Off", "Taylor Swift", "1989", "pop"),
    ("Blinding Lights", "The Weeknd", "After Hours", "pop"),
    ("Rolling in the Deep", "Adele", "21", "pop"),
    ("Respect", "Aretha Franklin", "I Never Loved a Man the Way I Love You", "soul"),
    ("Superstition", "Stevie Wonder", "Talking Book", "soul"),
    ("One More Time", "Daft Punk", "Discovery", "electronic"),
    ("Around the World", "Daft Punk", "Homework", "electronic"),
    ("Three Little Birds", "Bob Marley & The Wailers", "Exodus", "reggae"),
    ("Jolene", "Dolly Parton", "Jolene", "country"),
    ("Lose Yourself", "Eminem", "8 Mile", "hip hop"),
    ("The Thrill Is Gone", "B.B. King", "Completely Well", "blues"),
)
"""The built-in catalog of the ``sim`` backend, used when ``sim.catalog`` is not given."""

KNOWN_GENRES = (
    "jazz", "classical", "rock", "pop", "soul", "funk", "blues", "country", "folk", "reggae",
    "electronic", "dance", "house", "techno", "ambient", "hip hop", "rap", "r&b", "metal", "punk",
    "indie", "latin", "k-pop", "disco", "gospel", "opera", "piano", "lo-fi", "chill", "swing",
)  # fmt: skip
"""Genres "play some X" may name; the real backend searches these with Spotify's genre filter."""

# Words around the thing to play ("play *some* jazz *music*"): dropped before matching.
_LEADING = re.compile(
    r"^(?:(?:a )?(?:little |bit )+(?:of )?|some |any |more )?"
    r"(?:(?P<by>(?:songs?|tracks?|music|something|anything|stuff) (?:by|from) )|"
    r"(?:the )?(?P<kind>song|track|album|record|artist|band|genre)s? )?",
    re.IGNORECASE,
)
_TRAILING = re.compile(r"(?: (?:music|songs|tracks|please|for me|again|now))+$", re.IGNORECASE)
_KIND_WORDS: dict[str, MatchKind] = {
    "song": "track",
    "track": "track",
    "album": "album",
    "record": "album",
    "artist": "artist",
    "band": "artist",
    "genre": "genre",
}
_ANYTHING = frozenset({"", "music", "something", "anything", "songs", "tracks", "tunes"})
# Ignored when comparing names: "The Beatles" is "beatles", "Bob Marley & The Wailers" has no "&".
_NOISE_WORDS = frozenset({"the", "a", "an", "and"})


def clean_query(query: str) -> tuple[str, SearchKind]:
    """The thing to play, without filler words, and the kind the words say it is.

    ``"some jazz music"`` → ``("jazz", "any")``; ``"songs by Miles Davis"`` → ``("Miles Davis",
    "artist")``; ``"the album Abbey Road"`` → ``("Abbey Road", "album")``. A query that names
    nothing in particular ("music", "something") comes back empty, meaning "play anything".
    """
    text = " ".join(query.strip().strip(".!?\"'").split())
    kind: SearchKind = "any"
    match = _LEADING.match(text)
    if match and match.end() < len(text):
        if match.group("kind"):
            kind = _KIND_WORDS[match.group("kind").lower()]
        elif match.group("by"):
            kind = "artist"
        text = text[match.end() :]
    trimmed = _TRAILING.sub("", text) or text
    if normalize(trimmed) in _ANYTHING:
        return "", "any"
    return trimmed, kind


def normalize(text: str) -> str:
    """Lowercase, accents and punctuation removed, noise words dropped: "Gymnopédie No. 1" → "gymnopedie no 1"."""
    decomposed = unicodedata.normalize("NFKD", text.casefold())
    plain = "".join(char for char in decomposed if not unicodedata.combining(char))
    words = re.sub(r"[^\w]+", " ", plain.replace("'", "")).split()
    return " ".join(word for word in words if word not in _NOISE_WORDS)


@dataclass(frozen=True)
class Match:
    """A way a query matches the catalog: a track, or every track of an artist, album or genre."""

    kind: MatchKind
    name: str
    tracks: tuple[CatalogEntry, ...]
    score: int
    """4 the whole name, 3 every word of it, 2 every word across title and artist, 1 a near miss."""


EXACT, WORDS, COMBINED, NEAR = 4, 3, 2, 1
NEAR_RATIO = 0.8
"""How alike a query and a name must be to count as a near miss ("Bohemian Rapsody")."""
KIND_ORDER: tuple[MatchKind, ...] = ("track", "artist", "album", "genre")
"""Among equally good matches, the more specific kind wins ("Thriller": the song, not the album)."""


def _score(query: str, name: str) -> int:
    if not query or not name:
        return 0
    if query == name:
        return EXACT
    if set(query.split()) <= set(name.split()):
        return WORDS
    return NEAR if difflib.SequenceMatcher(None, query, name).ratio() >= NEAR_RATIO else 0


def find(catalog: tuple[CatalogEntry, ...], query: str, kind: SearchKind = "any") -> list[Match]:
    """Every way ``query`` matches ``catalog``, best first. Empty when nothing matches.

    The query should already be cleaned (:func:`clean_query`). Artists, albums and genres are
    matched once each, with all their tracks in catalog order.
    """
    wanted = normalize(query)
    # Tracks are grouped by title and artist (two artists may share a title); the rest by name.
    groups: dict[tuple[MatchKind, str], tuple[str, list[CatalogEntry]]] = {}
    for entry in catalog:
        fields: tuple[tuple[MatchKind, str | None], ...] = (
            ("track", entry.track),
            ("artist", entry.artist),
            ("album", entry.album),
            ("genre", entry.genre),
        )
        for group_kind, value in fields:
            if value is None or kind not in ("any", group_kind):
                continue
            key = normalize(f"{value} {entry.artist}" if group_kind == "track" else value)
            groups.setdefault((group_kind, key), (value, []))[1].append(entry)
    matches = []
    for (group_kind, _), (name, tracks) in groups.items():
        score = _score(wanted, normalize(name))
        if group_kind == "track" and score < WORDS and wanted:
            # "so what miles davis", "here comes the sun by the beatles": title and artist together.
            together = set(normalize(f"{name} {tracks[0].artist}").split())
            if set(wanted.split()) - {"by"} <= together:
                score = COMBINED
        if score:
            matches.append(Match(group_kind, name, tuple(tracks), score))
    matches.sort(key=lambda match: (-match.score, KIND_ORDER.index(match.kind)))
    return matches


def describe(entry: CatalogEntry) -> str:
    """How a track is named in replies: "Clair de Lune by Claude Debussy"."""
    return f"{entry.track} by {entry.artist}"


def suggestions(catalog: tuple[CatalogEntry, ...], count: int = 3) -> str:
    """A few things the user could ask for instead, for "nothing matches" messages."""
    genres = sorted({entry.genre for entry in catalog if entry.genre})
    titles = ", ".join(f'"{entry.track}"' for entry in catalog[:count])
    artists = ", ".join(dict.fromkeys(entry.artist for entry in catalog[:count]))
    parts = [f"a title ({titles})", f"an artist ({artists})"]
    if genres:
        parts.append(f"a genre ({', '.join(genres)})")
    return "; ".join(parts)
