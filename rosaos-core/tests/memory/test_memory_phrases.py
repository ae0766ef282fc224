"""The offline engine's sentences about memory: places, facts, aliases, forgetting."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from rosaos.memory.memory_phrases import (
    Forget,
    ForgetPlace,
    ForgetSightings,
    GoToPlace,
    ListPlaces,
    Recall,
    RecallSightings,
    RememberNote,
    RememberPlace,
    ShowSighting,
    UnknownPlace,
    apply_preferences,
    read_memory_request,
    resolve_aliases,
)

KNOWN = {"kitchen", "charging corner"}


@pytest.mark.parametrize(
    ("said", "expected"),
    [
        ("Remember this spot as the kitchen", RememberPlace("the kitchen")),
        ("save this place as kitchen.", RememberPlace("the kitchen")),
        ("dog, remember this spot as the doghouse", RememberPlace("the doghouse", robot="dog")),
        ("The charging corner is at x 2, y -1", RememberPlace("the charging corner", 2.0, -1.0)),
        (
            "the porch is at x 1.5 y minus 3 facing 90 degrees",
            RememberPlace("the porch", 1.5, -3.0, math.pi / 2),
        ),
        ("the attic stairs are at x 1, y 1", RememberPlace("the attic stairs", 1.0, 1.0)),
        ("Go to the kitchen", GoToPlace("the kitchen")),
        ("head to the kitchen please", GoToPlace("the kitchen")),
        ("drive over to the charging corner", GoToPlace("the charging corner")),
        ("come back to the kitchen", GoToPlace("the kitchen")),
        ("turtlebot, go to the kitchen", GoToPlace("the kitchen", "turtlebot")),
        ("go to the attic", UnknownPlace("the attic")),
        ("Which places do you know?", ListPlaces()),
        ("forget the kitchen", ForgetPlace("the kitchen")),
        ("forget that my name is Sam", Forget("my name is sam")),
        ("call the dog Rex", RememberNote("alias", "rex", "the dog")),
        ("the dog is called Rex", RememberNote("alias", "rex", "the dog")),
        ("my name is Sam", RememberNote("fact", "my name", "Sam")),
        (
            "I like my reading light at 40 percent",
            RememberNote("preference", "my reading light", "40 percent"),
        ),
        (
            "remember that the kids go to bed at 8",
            RememberNote("fact", "the kids go to bed at 8", "the kids go to bed at 8"),
        ),
        ("What do you remember?", Recall()),
        ("Where did you last see someone?", RecallSightings()),
        ("has anyone been in the kitchen today?", RecallSightings("the kitchen", today=True)),
        ("forget what you saw", ForgetSightings()),
        ("Show me", ShowSighting()),
        ("show me the picture please", ShowSighting()),
        ("let me see them", ShowSighting()),
        ("show me a dance", None),  # the Reachy's
        ("turn on the kitchen light", None),
    ],
)
def test_a_sentence_reads_as_its_memory_request(said: str, expected: object) -> None:
    assert read_memory_request(said, KNOWN) == expected


def test_go_to_an_unknown_place_is_left_alone_when_no_place_is_known() -> None:
    assert read_memory_request("go to sleep", set()) is None


def test_an_alias_is_replaced_as_a_whole_word_in_any_case() -> None:
    aliases = {"rex": "the dog"}
    assert resolve_aliases("Rex, walk forward one metre", aliases) == "the dog, walk forward one metre"
    assert resolve_aliases("turn on the rexroth lamp", aliases) == "turn on the rexroth lamp"


def test_a_command_the_engine_understands_is_not_read_as_an_alias(tmp_path: Path) -> None:
    from rosaos.intents.understanding.match_result import MatchResult
    from rosaos.memory.store import MemoryStore
    from rosaos.models.memory_turn import memory_request

    store = MemoryStore.open(tmp_path)
    asks = MatchResult(text="call the turtlebot back", kind="clarify", reply="Which robot?")
    nothing = MatchResult(text="call the dog rex", kind="no_match", reply="Sorry")
    assert memory_request("call the turtlebot back", store, lambda text: asks) is None
    assert memory_request("call the dog Rex", store, lambda text: nothing) == RememberNote(
        "alias", "rex", "the dog"
    )


LIKED = {"my reading light": "40 percent"}


@pytest.mark.parametrize(
    "said",
    ["set my reading light", "Set my reading light please.", "put my reading light how I like it",
     "my reading light the way I like it", "could you set my reading light"],
)  # fmt: skip
def test_a_preference_fills_in_the_value_a_request_leaves_out(said: str) -> None:
    assert apply_preferences(said, LIKED) == "set my reading light to 40 percent"


@pytest.mark.parametrize(
    "said", ["set my reading light to 80 percent", "turn off my reading light", "set the hall light"]
)
def test_a_request_with_its_own_value_or_another_action_is_left_alone(said: str) -> None:
    assert apply_preferences(said, LIKED) == said
