"""Device state in words: yes/no material, positions in metres and degrees, never radians."""

from __future__ import annotations

import math

from rosaos.intents.grammar.state_words import battery, describe, doing, position


def test_a_docked_robot_is_at_its_dock() -> None:
    assert position({"x": 0.0, "y": 0.0, "yaw": 0.0, "docked": True}) == "at its dock"


def test_a_position_is_said_in_metres_from_the_dock_and_a_heading_in_words() -> None:
    state = {"x": 1.4, "y": 0.02, "yaw": math.pi / 2, "docked": False}
    assert position(state) == "1.4 m ahead of its dock, facing left"


def test_a_robot_without_a_dock_counts_from_where_it_started_and_degrees_are_degrees() -> None:
    state = {"x": -0.5, "y": -1.25, "yaw": math.radians(-45)}
    assert (
        position(state) == "0.5 m behind and 1.2 m to the right of where it started, facing 45° to the right"
    )


def test_a_robot_back_where_it_started_is_said_to_be_there() -> None:
    """ "The dog is where it started", not "at where it started" (fresh-12's reply)."""
    assert position({"x": 0.01, "y": 0.0, "yaw": 0.0}) == "where it started, facing ahead"
    assert (position({"x": 0.01, "y": 0.0, "yaw": 0.0, "docked": False}) or "").startswith("by its dock")


def test_battery_reads_a_fraction_or_a_percentage() -> None:
    assert battery({"battery": 0.913}) == "91%"
    assert battery({"battery": 55}) == "55%"
    assert battery({"on": True}) is None


def test_what_a_device_is_doing_comes_from_its_state() -> None:
    assert doing({"linear": 0.2, "angular": 0.0}) == "moving"
    assert doing({"is_playing": True}) == "playing"
    assert doing({"speaking": True}) == "speaking"
    assert doing({"linear": 0.0, "angular": 0.0, "on": True}) is None


def test_describe_never_says_radians() -> None:
    said = " ".join(describe("turtlebot", {"x": 2.0, "y": 0.0, "yaw": 3.1, "docked": False, "battery": 0.5}))
    assert "rad" not in said and "facing back" in said and "50%" in said
