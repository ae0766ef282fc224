"""Emotions and dances: the built-in keyframes, and Pollen's recorded moves when they are cached."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rosaos_reachy.emotions import MoveLibrary, UnknownMove
from rosaos_reachy.robot import HeadPose, Posture
from rosaos_reachy.settings import DANCES_DATASET, EMOTIONS_DATASET

START = Posture(HeadPose(yaw=20.0, pitch=-5.0), (10.0, 10.0), 15.0)


@pytest.fixture
def library(tmp_path: Path) -> MoveLibrary:
    """The built-in set, with an empty Hugging Face cache (nothing recorded is available)."""
    moves = MoveLibrary(EMOTIONS_DATASET, DANCES_DATASET, cache_dir=tmp_path / "hf")
    moves.refresh()
    return moves


def test_without_a_cached_dataset_the_built_in_set_is_used(library: MoveLibrary) -> None:
    listing = library.listing()
    assert listing["emotions"]["source"] == "built-in" and listing["dances"]["source"] == "built-in"
    assert {"happy", "sad", "surprised", "curious", "yes", "no"} <= set(listing["emotions"]["built_in"])
    assert {"groove", "sway", "robot"} == set(listing["dances"]["built_in"])


@pytest.mark.parametrize("kind", ["emotions", "dances"])
def test_every_built_in_move_starts_and_ends_where_the_robot_was(library: MoveLibrary, kind: str) -> None:
    for name in library.names(kind):
        move, end = library.resolve(kind, name).move(START)
        assert end == START
        assert move.posture_at(0.0) == START, name
        assert move.posture_at(move.duration) == START, name
        assert 0.5 < move.duration < 8.0, name


def test_a_nod_moves_the_head_down_relative_to_where_it_looks(library: MoveLibrary) -> None:
    move, _ = library.resolve("emotions", "nod").move(START)
    lowest = max(move.posture_at(t / 20).head.pitch for t in range(int(move.duration * 20)))
    assert lowest == pytest.approx(START.head.pitch + 15, abs=0.5)
    assert all(move.posture_at(t / 20).head.yaw == pytest.approx(20.0) for t in range(20))


def test_the_sdk_evaluates_a_built_in_move_in_its_own_units(library: MoveLibrary) -> None:
    move, _ = library.resolve("emotions", "happy").move(START)
    head, antennas, body_yaw = move.evaluate(0.0)
    assert head.shape == (4, 4) and len(antennas) == 2
    assert body_yaw == pytest.approx(0.2618, abs=1e-3)  # 15 degrees, in radians


def test_aliases_and_spelling_resolve(library: MoveLibrary) -> None:
    assert library.resolve("emotions", "Shake").name == "no"
    assert library.resolve("emotions", " HAPPY ").name == "happy"


def test_an_unknown_name_lists_what_there_is(library: MoveLibrary) -> None:
    with pytest.raises(UnknownMove, match="happy, sad"):
        library.resolve("emotions", "jealous")


def fake_cached_dataset(cache: Path, name: str, moves: list[str]) -> None:
    """A dataset laid out exactly as huggingface_hub caches it: refs/main → snapshots/<rev>/."""
    repo = cache / f"datasets--{name.replace('/', '--')}"
    revision = "0" * 40
    (repo / "refs").mkdir(parents=True)
    (repo / "refs" / "main").write_text(revision)
    snapshot = repo / "snapshots" / revision
    snapshot.mkdir(parents=True)
    identity = [[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, 1.0]]
    for move in moves:
        frames = [{"head": identity, "antennas": [0.0, 0.0], "body_yaw": 0.0} for _ in range(20)]
        data = {"description": move, "time": [i * 0.05 for i in range(20)], "set_target_data": frames}
        (snapshot / f"{move}.json").write_text(json.dumps(data))


def test_a_cached_recorded_dataset_is_used_and_named(tmp_path: Path) -> None:
    cache = tmp_path / "hf"
    fake_cached_dataset(cache, EMOTIONS_DATASET, ["cheerful1", "amazed1"])
    moves = MoveLibrary(EMOTIONS_DATASET, DANCES_DATASET, cache_dir=cache)
    moves.refresh()
    listing = moves.listing()
    assert listing["emotions"]["source"] == f"dataset {EMOTIONS_DATASET}"
    assert listing["emotions"]["recorded"] == ["amazed1", "cheerful1"]
    assert listing["dances"]["source"] == "built-in"
    choice = moves.resolve("emotions", "cheerful1")
    assert choice.recorded is not None and choice.source == f"dataset {EMOTIONS_DATASET}"
    move, end = choice.move(START)
    assert move.duration == pytest.approx(0.5 + 0.95, abs=0.01)  # lead-in, then the recording (SDK timing)
    assert end.head.yaw == pytest.approx(0.0, abs=1e-6)
    assert moves.resolve("emotions", "happy").source == "built-in"  # built-ins stay available
