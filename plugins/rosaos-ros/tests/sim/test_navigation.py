"""The simulated Nav2's planner: around the pillars, straight when clear, and refusals with reasons."""

from __future__ import annotations

import itertools
import math

import pytest

from rosaos_ros.sim.navigation import CLEARANCE, Obstacles, PlanningError, path_length, plan_path


def test_a_clear_line_is_one_straight_leg() -> None:
    assert plan_path((0.0, 0.0), (1.0, 1.0)) == [(1.0, 1.0)]


def test_a_path_past_the_red_pillar_keeps_its_clearance_and_ends_on_the_goal() -> None:
    waypoints = plan_path((0.0, 0.0), (3.5, 0.0))  # the red pillar stands at (2, 0)
    assert waypoints[-1] == (3.5, 0.0)
    assert len(waypoints) >= 2, "a straight line would go through the pillar"
    legs = [(0.0, 0.0), *waypoints]
    assert all(Obstacles().clear_line(a, b) for a, b in itertools.pairwise(legs))
    assert path_length((0.0, 0.0), waypoints) < 3.5 + 1.0, "a detour, not a tour"


def test_a_goal_inside_a_pillar_is_refused_naming_the_pillar() -> None:
    with pytest.raises(PlanningError, match=r"inside an obstacle: a pillar stands at \(2, 0\)"):
        plan_path((0.0, 0.0), (2.0, 0.1))


def test_a_goal_walled_in_by_obstacles_is_unreachable() -> None:
    ring = tuple(
        (5 + 0.5 * math.cos(a / 8 * math.tau), 5 + 0.5 * math.sin(a / 8 * math.tau)) for a in range(8)
    )
    with pytest.raises(PlanningError, match="no path reaches"):
        plan_path((0.0, 0.0), (5.0, 5.0), Obstacles(ring, CLEARANCE))


def test_a_goal_beyond_the_planning_area_is_refused() -> None:
    with pytest.raises(PlanningError, match="too far"):
        plan_path((0.0, 0.0), (900.0, 900.0), Obstacles(((450.0, 450.0),), CLEARANCE))
