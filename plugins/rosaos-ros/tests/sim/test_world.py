"""The simulated base's physics: integration, the command timeout, limits, the dock, the battery."""

from __future__ import annotations

import math

import pytest
from pydantic import ValidationError

from rosaos_ros.profiles import Limits
from rosaos_ros.sim.world import Autopilot, DiffDriveWorld, DockPose, SimState

LIMITS = Limits(linear=1.0, angular=3.0)


def run(
    world: DiffDriveWorld, seconds: float, twist: tuple[float, float] | None = None, start: float = 0.0
) -> float:
    """Step the world at 50 Hz for ``seconds``, sending ``twist`` every step if given; returns the end time."""
    now = start
    for _ in range(round(seconds * 50)):
        now += 0.02
        if twist is not None:
            world.command(*twist, now)
        world.step(0.02, now)
    return now


def test_a_straight_command_integrates_into_x() -> None:
    world = DiffDriveWorld(LIMITS)
    run(world, 2.0, (0.25, 0.0))
    assert world.x == pytest.approx(0.5)
    assert (world.y, world.yaw) == (pytest.approx(0.0), pytest.approx(0.0))


def test_a_turn_in_place_is_counter_clockwise_for_positive_angular() -> None:
    world = DiffDriveWorld(LIMITS)
    run(world, 1.0, (0.0, math.pi / 2))
    assert world.yaw == pytest.approx(math.pi / 2)
    assert (world.x, world.y) == (pytest.approx(0.0), pytest.approx(0.0))


def test_an_arc_follows_the_exact_circle() -> None:
    world = DiffDriveWorld(LIMITS)
    run(world, math.pi, (0.5, 0.5))  # a quarter circle of radius 1 m, counter-clockwise
    assert (world.x, world.y) == (pytest.approx(1.0, abs=1e-3), pytest.approx(1.0, abs=1e-3))


def test_the_base_stops_when_commands_stop_for_half_a_second() -> None:
    world = DiffDriveWorld(LIMITS)
    now = run(world, 1.0, (0.2, 0.0))
    run(world, 0.4, start=now)
    assert world.linear == 0.2  # still within the timeout
    run(world, 0.2, start=now + 0.4)
    assert (world.linear, world.stopped_by) == (0.0, "cmd_vel timeout")


def test_a_zero_twist_is_recorded_as_the_reason_for_stopping() -> None:
    world = DiffDriveWorld(LIMITS)
    now = run(world, 0.2, (0.2, 0.0))
    run(world, 0.1, (0.0, 0.0), start=now)
    assert (world.linear, world.stopped_by) == (0.0, "zero twist")


def test_hardware_limits_cap_what_the_wheels_do() -> None:
    world = DiffDriveWorld(LIMITS)
    run(world, 1.0, (5.0, -9.0))
    assert (world.linear, world.angular) == (1.0, -3.0)


def test_e_stop_holds_the_base_still() -> None:
    world = DiffDriveWorld(LIMITS, e_stop=True)
    run(world, 1.0, (0.2, 0.0))
    assert world.x == 0.0


def test_driving_off_the_dock_undocks() -> None:
    world = DiffDriveWorld.from_state(SimState(docked=True), LIMITS)
    run(world, 0.5, (0.2, 0.0))
    assert world.docked is False


def test_the_autopilot_backs_onto_a_dock_behind_the_robot() -> None:
    world = DiffDriveWorld.from_state(SimState(x=0.8, y=0.1), LIMITS)
    world.autopilot = Autopilot(0.0, 0.0, 0.0, speed=0.3, turn_speed=2.0)
    run(world, 10.0)
    assert world.autopilot is None
    assert world.on_dock_pose()


def test_the_battery_charges_on_the_dock_and_drains_off_it() -> None:
    docked = DiffDriveWorld.from_state(SimState(docked=True, battery=0.5), LIMITS)
    roaming = DiffDriveWorld.from_state(SimState(battery=0.5), LIMITS)
    run(docked, 10.0)
    run(roaming, 10.0, (0.2, 0.0))
    assert docked.battery > 0.5 > roaming.battery


def test_the_dock_is_where_a_docked_robot_starts() -> None:
    world = DiffDriveWorld.from_state(SimState(x=1.0, y=2.0, yaw=0.5, docked=True), LIMITS)
    assert world.dock == DockPose(x=1.0, y=2.0, yaw=0.5)


def test_sim_state_refuses_a_moving_start_and_a_docked_robot_away_from_its_dock() -> None:
    with pytest.raises(ValidationError, match="starts at rest"):
        SimState(linear=0.2)
    with pytest.raises(ValidationError, match="from the dock pose"):
        SimState(x=1.0, docked=True, dock=DockPose())
