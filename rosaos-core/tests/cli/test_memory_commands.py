"""``rosaos places`` and ``rosaos memory`` on the data directory's memory file."""

from __future__ import annotations

import json
import time
from pathlib import Path

from typer.testing import CliRunner

from rosaos.cli.root import app
from rosaos.memory.sightings import SightingLog
from rosaos.memory.store import MemoryStore
from rosaos.receipts import Receipt

runner = CliRunner()


def store(tmp_path: Path) -> MemoryStore:
    return MemoryStore.open(tmp_path / "data")


def test_places_add_rename_list_json_and_delete(tmp_path: Path) -> None:
    added = runner.invoke(app, ["places", "add", "the kitchen", "--x", "3.5", "--y", "0", "-d", "turtlebot",
                                "--anchor", "map:/maps/home.yaml"])  # fmt: skip
    assert added.exit_code == 0, added.output
    # The second place of the same robot takes its frame from the first.
    assert (
        runner.invoke(app, ["places", "add", "hall", "--x", "0", "--y", "1", "-d", "turtlebot"]).exit_code
        == 0
    )
    assert runner.invoke(app, ["places", "rename", "kitchen", "the galley"]).exit_code == 0
    listed = json.loads(runner.invoke(app, ["places", "--json"]).output)
    assert [(p["name"], p["anchor"]) for p in listed] == [
        ("the galley", "map:/maps/home.yaml"),
        ("hall", "map:/maps/home.yaml"),
    ]
    assert runner.invoke(app, ["places", "delete", "the galley"]).exit_code == 0
    assert [p.name for p in store(tmp_path).places()] == ["hall"]


def test_places_add_without_a_known_frame_says_to_pass_the_anchor(tmp_path: Path) -> None:
    result = runner.invoke(app, ["places", "add", "dock", "--x", "0", "--y", "0", "-d", "dog"])
    assert result.exit_code == 1
    assert "pass --anchor" in result.output


def test_a_non_finite_coordinate_is_refused_and_nothing_is_saved(tmp_path: Path) -> None:
    result = runner.invoke(
        app, ["places", "add", "x", "--x", "nan", "--y", "0", "-d", "t", "--anchor", "map"]
    )
    assert result.exit_code == 1 and "x: Input should be a finite number" in result.output
    assert store(tmp_path).places() == []


def test_memory_list_forget_export_and_clear(tmp_path: Path) -> None:
    memory = store(tmp_path)
    memory.save_note("alias", "rex", "the dog", "call the dog Rex")
    memory.save_note("fact", "my name", "Sam", "my name is Sam")
    assert "call the dog Rex" in runner.invoke(app, ["memory", "list"]).output
    forgot = runner.invoke(app, ["memory", "forget", "my", "name"])
    assert forgot.exit_code == 0 and "forgot: my name is Sam" in forgot.output
    exported = json.loads(runner.invoke(app, ["memory", "export"]).output)
    assert [note["key"] for note in exported["notes"]] == ["rex"] and exported["places"] == []
    assert runner.invoke(app, ["memory", "forget", "nothing", "like", "this"]).exit_code == 1
    assert runner.invoke(app, ["memory", "clear", "--yes"]).exit_code == 0
    assert store(tmp_path).notes() == []


def test_memory_sightings_lists_them_and_memory_picture_prints_the_newest_pictures_file(
    tmp_path: Path,
) -> None:
    images = tmp_path / "data" / "images"
    images.mkdir(parents=True)
    (images / "turtlebot-1.jpg").write_bytes(b"\xff\xd8 a picture")
    log = SightingLog(store(tmp_path), images_dir=images)
    person = {"x": 1.0, "y": 2.0, "frame": "odom", "anchor": "odom:turtlebot:1"}
    with_picture, without = (
        Receipt(device="turtlebot", tool="detect_people", ok=True, started=time.time() - age, duration=0.1,
                result=json.dumps({"people": [person], "image": image}))
        for age, image in ((60, "turtlebot-1.jpg"), (0, "turtlebot-deleted.jpg"))
    )  # fmt: skip
    [first] = log.record_receipts([with_picture])
    [second] = log.record_receipts([without])

    listed = json.loads(runner.invoke(app, ["memory", "sightings", "--json"]).output)
    assert [(s["id"], s["picture_file"]) for s in listed] == [
        (second.id, None),
        (first.id, str((images / "turtlebot-1.jpg").resolve())),
    ]
    assert "turtlebot" in runner.invoke(app, ["memory", "sightings"]).output
    # The newest with a picture: the second one's file was deleted.
    newest = runner.invoke(app, ["memory", "picture"])
    assert newest.exit_code == 0 and newest.output.strip() == str((images / "turtlebot-1.jpg").resolve())
    gone = runner.invoke(app, ["memory", "picture", str(second.id)])
    assert gone.exit_code == 1 and f"sighting {second.id} has no picture" in gone.output
    unknown = runner.invoke(app, ["memory", "picture", "99"])
    assert unknown.exit_code == 1 and "no sighting 99" in unknown.output


def test_memory_picture_without_any_sighting_says_how_to_list_them(tmp_path: Path) -> None:
    result = runner.invoke(app, ["memory", "picture"])
    assert result.exit_code == 1 and "rosaos memory sightings" in result.output
