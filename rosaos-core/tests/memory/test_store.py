"""The memory file: places with their frame, notes by kind, owner-only, durable across opens."""

from __future__ import annotations

import stat
import threading
import time
from pathlib import Path

import pytest

from rosaos.memory.store import MemoryRequestError, MemoryStore, Place, place_key


def kitchen(**changes: object) -> Place:
    fields = dict(name="the kitchen", device="turtlebot", frame="map", anchor="map:/maps/home.yaml",
                  x=3.5, y=0.0, yaw=0.0, saved_at=time.time())  # fmt: skip
    return Place.model_validate(fields | changes)


def test_a_place_survives_reopening_with_its_frame_and_is_found_by_any_spelling(tmp_path: Path) -> None:
    MemoryStore.open(tmp_path).save_place(kitchen())
    found = MemoryStore.open(tmp_path).place("The Kitchen")
    assert found is not None and (found.x, found.frame, found.anchor) == (3.5, "map", "map:/maps/home.yaml")
    assert place_key("  the   Kitchen ") == "kitchen"


def test_the_file_is_owner_only(tmp_path: Path) -> None:
    store = MemoryStore.open(tmp_path)
    assert stat.S_IMODE(store.path.stat().st_mode) == 0o600


def test_an_unknown_place_error_names_the_known_ones_and_how_to_save_one(tmp_path: Path) -> None:
    store = MemoryStore.open(tmp_path)
    store.save_place(kitchen())
    with pytest.raises(
        MemoryRequestError, match=r"known places: the kitchen.*remember this spot as the attic"
    ):
        store.require_place("the attic")


def test_rename_refuses_a_taken_name_and_forget_deletes(tmp_path: Path) -> None:
    store = MemoryStore.open(tmp_path)
    store.save_place(kitchen())
    store.save_place(kitchen(name="the hall"))
    with pytest.raises(MemoryRequestError, match="already a place called"):
        store.rename_place("kitchen", "hall")
    assert store.rename_place("kitchen", "the galley").name == "the galley"
    store.forget_place("galley")
    assert [p.name for p in store.places()] == ["the hall"]


def test_a_non_finite_coordinate_is_refused() -> None:
    with pytest.raises(ValueError, match="finite"):
        kitchen(x=float("nan"))


def test_notes_replace_by_kind_and_key_and_forget_matches_words(tmp_path: Path) -> None:
    store = MemoryStore.open(tmp_path)
    store.save_note("alias", "Rex", "the dog", "call the dog Rex")
    store.save_note("alias", "rex", "the turtlebot", "call the turtlebot Rex")
    store.save_note("fact", "my name", "Sam", "my name is Sam")
    assert store.aliases() == {"rex": "the turtlebot"}
    assert [n.said for n in store.forget_notes("my name is sam")] == ["my name is Sam"]
    assert store.clear() == (0, 1)


def test_notes_and_places_read_again_see_every_write_here_in_a_thread_or_elsewhere(tmp_path: Path) -> None:
    # The kernel keeps its last reading of the notes (it reads them on every event); a name given
    # a moment ago, here or by `rosaos memory` in another process, must still count at once.
    kernel = MemoryStore.open(tmp_path)
    assert kernel.aliases() == {}
    kernel.save_note("alias", "rex", "the dog", "call the dog rex")
    assert kernel.aliases() == {"rex": "the dog"}
    MemoryStore.open(tmp_path).save_note("alias", "robbie", "the turtlebot", "call the turtlebot robbie")
    assert kernel.aliases() == {"rex": "the dog", "robbie": "the turtlebot"}
    writer = threading.Thread(
        target=lambda: kernel.save_note("preference", "reading light", "40 percent", "x")
    )
    writer.start()
    writer.join()
    assert [note.key for note in kernel.notes()] == ["rex", "robbie", "reading light"]
    kernel.forget_notes("rex")
    assert kernel.aliases() == {"robbie": "the turtlebot"}
    assert kernel.places() == []
    MemoryStore.open(tmp_path).save_place(kitchen())
    assert [place.name for place in kernel.places()] == ["the kitchen"]
    kernel.rename_place("the kitchen", "the galley")
    assert [place.name for place in kernel.places()] == ["the galley"]
    MemoryStore.open(tmp_path).clear()
    assert kernel.notes() == [] and kernel.aliases() == {} and kernel.places() == []
