"""Small catalogs the simulator tests share (imported by name: the conftest puts this folder on sys.path)."""

from __future__ import annotations

ALBUMS = [
    {"track": "So What", "artist": "Miles Davis", "album": "Kind of Blue", "genre": "jazz"},
    {"track": "Freddie Freeloader", "artist": "Miles Davis", "album": "Kind of Blue", "genre": "jazz"},
    {"track": "Blue in Green", "artist": "Miles Davis", "album": "Kind of Blue", "genre": "jazz"},
    {"track": "Take Five", "artist": "The Dave Brubeck Quartet", "album": "Time Out", "genre": "jazz"},
    {
        "track": "Clair de Lune",
        "artist": "Claude Debussy",
        "album": "Suite bergamasque",
        "genre": "classical",
    },
]
