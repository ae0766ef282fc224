"""Task files: the format of ``../shared/bench/README.md``, and errors that name the file and the key."""

from __future__ import annotations

from pathlib import Path

import pytest

from rosaos.bench.runner import select_tasks
from rosaos.bench.tasks import TaskFileError, find_task_files, load_task_file, load_task_files

WORLD = """\
name: desk
world:
  lamp:
    driver: tapo
    state: {on: false, brightness: 100}
  spotify:
    driver: spotify
    state: {is_playing: false, repeat: off}
"""


def write(tmp_path: Path, text: str, name: str = "desk.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def error_of(path: Path) -> str:
    with pytest.raises(TaskFileError) as caught:
        load_task_file(path)
    return str(caught.value)


def test_on_and_off_stay_strings_as_keys_and_values(tmp_path: Path) -> None:
    path = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: Lamp on, expect: {lamp: {on: true}}}\n")
    task_file = load_task_file(path)
    assert task_file.world["lamp"].state == {"on": False, "brightness": 100}
    assert task_file.world["spotify"].state["repeat"] == "off"
    assert task_file.tasks[0].expect == {"lamp": {"on": True}}


def test_setup_overrides_the_initial_state_key_by_key(tmp_path: Path) -> None:
    path = write(
        tmp_path, WORLD + "tasks:\n  - {id: t1, say: Lamp off, setup: {lamp: {on: true}}, expect: {}}\n"
    )
    task_file = load_task_file(path)
    initial = task_file.initial_state(task_file.tasks[0])
    assert initial["lamp"] == {"on": True, "brightness": 100}


def test_a_missing_key_names_the_file_the_task_and_the_key(tmp_path: Path) -> None:
    path = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: Lamp on}\n")
    assert error_of(path) == f"{path}: tasks[0] (t1).expect: Field required"


def test_an_unknown_key_is_an_error(tmp_path: Path) -> None:
    path = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: Lamp on, expect: {}, exepct: {}}\n")
    assert f"{path}: tasks[0] (t1).exepct: unknown key" in error_of(path)


def test_an_unknown_device_names_the_devices_that_exist(tmp_path: Path) -> None:
    path = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: Lamp on, expect: {lamp2: {on: true}}}\n")
    assert error_of(path) == (
        f"{path}: tasks[0] (t1).expect.lamp2: unknown device; devices in this world: lamp, spotify"
    )


def test_a_malformed_operator_says_what_it_needs(tmp_path: Path) -> None:
    path = write(
        tmp_path, WORLD + "tasks:\n  - {id: t1, say: Dim, expect: {lamp: {brightness: {between: [5]}}}}\n"
    )
    assert error_of(path) == (
        f"{path}: tasks[0] (t1).expect.lamp.brightness.between: needs [low, high], two numbers; got [5]"
    )


def test_an_operator_mixed_with_keys_is_an_error(tmp_path: Path) -> None:
    path = write(
        tmp_path, WORLD + "tasks:\n  - {id: t1, say: Dim, expect: {lamp: {brightness: {lt: 50, x: 1}}}}\n"
    )
    assert "tasks[0] (t1).expect.lamp.brightness: an operator stands alone" in error_of(path)


def test_a_bad_reply_regex_is_an_error(tmp_path: Path) -> None:
    path = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: Hi, expect: {}, reply: '(unclosed'}\n")
    assert f"{path}: tasks[0] (t1).reply: Value error, not a valid regular expression" in error_of(path)


def test_a_task_id_used_twice_in_a_file_is_an_error(tmp_path: Path) -> None:
    path = write(
        tmp_path, WORLD + "tasks:\n  - {id: t1, say: A, expect: {}}\n  - {id: t1, say: B, expect: {}}\n"
    )
    assert error_of(path) == f"{path}: tasks[1] (t1).id: 't1' appears twice in this file; ids must be unique"


def test_task_ids_must_be_unique_across_files(tmp_path: Path) -> None:
    first = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: A, expect: {}}\n", "a.yaml")
    second = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: B, expect: {}}\n", "b.yaml")
    with pytest.raises(TaskFileError) as caught:
        load_task_files([first, second])
    assert str(caught.value).startswith(f"{second}: tasks[0] (t1).id: 't1' is already used in {first};")


def test_every_problem_of_every_file_is_reported_at_once(tmp_path: Path) -> None:
    first = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: A}\n", "a.yaml")
    second = write(tmp_path, "name: [", "b.yaml")
    with pytest.raises(TaskFileError) as caught:
        load_task_files([first, second])
    lines = str(caught.value).splitlines()
    assert lines[0] == f"{first}: tasks[0] (t1).expect: Field required"
    assert lines[1].startswith(f"{second}: not valid YAML")


def test_a_file_that_is_not_a_mapping_says_what_a_task_file_is(tmp_path: Path) -> None:
    path = write(tmp_path, "- just\n- a list\n")
    assert error_of(path) == f"{path}: a task file is a mapping with name, world and tasks (see the README)"


def test_directories_give_their_yaml_files_in_order(tmp_path: Path) -> None:
    write(tmp_path, "x", "b.yaml")
    write(tmp_path, "x", "a.yml")
    write(tmp_path, "x", "notes.txt")
    assert [p.name for p in find_task_files([tmp_path])] == ["a.yml", "b.yaml"]


def test_a_missing_path_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(TaskFileError, match=r"nope\.yaml: no such file or directory"):
        find_task_files([tmp_path / "nope.yaml"])


def test_tasks_are_selected_by_glob_on_their_id(tmp_path: Path) -> None:
    path = write(
        tmp_path,
        WORLD + "tasks:\n  - {id: lamp-on, say: A, expect: {}}\n  - {id: music-play, say: B, expect: {}}\n",
    )
    [selection] = select_tasks([load_task_file(path)], ["lamp-*"])
    assert [task.id for task in selection.tasks] == ["lamp-on"]
    assert select_tasks([load_task_file(path)], ["robot-*"]) == []


def test_say_may_be_a_conversation_with_delays(tmp_path: Path) -> None:
    tasks = "tasks:\n  - id: t1\n    say: [Lamp on, {after: 3, text: Play jazz}]\n    settle: 180\n    expect: {}\n"
    [task] = load_task_file(write(tmp_path, WORLD + tasks)).tasks
    assert [(item.text, item.after) for item in task.utterances] == [("Lamp on", 0.0), ("Play jazz", 3.0)]
    assert (task.settle, task.said) == (180, "Lamp on / Play jazz")


def test_settle_defaults_to_a_minute_and_stops_at_ten(tmp_path: Path) -> None:
    [task] = load_task_file(write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: Lamp on, expect: {}}\n")).tasks
    assert task.settle == 60
    path = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: Lamp on, settle: 601, expect: {}}\n")
    assert f"{path}: tasks[0] (t1).settle: Input should be less than or equal to 600" in error_of(path)


def test_a_blank_or_negative_item_is_an_error(tmp_path: Path) -> None:
    blank = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: [Lamp on, '  '], expect: {}}\n")
    assert "not blank" in error_of(blank)
    early = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: [{after: -1, text: Lamp on}], expect: {}}\n")
    assert "after: Input should be greater than or equal to 0" in error_of(early)
    empty = write(tmp_path, WORLD + "tasks:\n  - {id: t1, say: [], expect: {}}\n")
    assert "say" in error_of(empty)
