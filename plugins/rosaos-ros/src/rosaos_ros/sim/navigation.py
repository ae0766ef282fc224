"""The simulated Nav2: plan a path around the pillars, then follow it at the profile's speeds.

A real TurtleBot 4 navigates with Nav2 on a map; the simulator stands in for it with what a test
needs to trust a ``go_to``: a grid A* over the four pillars (inflated by the robot's radius, as
a costmap would), the path shortened where a straight line is clear, and a follower that turns
toward each waypoint and drives to it. The planner is pure, so it is tested on its own.

Goals inside an obstacle, or that no path reaches within the planning area, fail at once with a
reason, as Nav2's planner server does.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field

from rosaos_ros.messages import wrap_angle
from rosaos_ros.sim.images import PILLAR_WIDTH, PILLARS
from rosaos_ros.sim.world import Autopilot, DiffDriveWorld

ROBOT_RADIUS = 0.2
"""Metres: about a TurtleBot 4's footprint radius (it is 0.34 m across)."""
CLEARANCE = PILLAR_WIDTH / 2 + ROBOT_RADIUS + 0.05
"""How near a pillar's centre the robot's centre may come: the inflated obstacle."""
CELL = 0.1
"""Grid resolution, metres."""
MARGIN = 3.0
"""Metres around the start, the goal and the pillars that the planner may use."""
MAX_CELLS = 250_000
"""The planning area's limit: a goal far beyond it is refused rather than planned for minutes."""
WAYPOINT_REACHED = 0.08
"""Metres from an intermediate waypoint at which the follower heads for the next one."""

Point = tuple[float, float]


class PlanningError(ValueError):
    """No path: the goal is inside an obstacle, outside the planning area, or cut off."""


@dataclass(frozen=True)
class Obstacles:
    """Round obstacles (the pillars), each as a centre; the robot keeps ``clearance`` from it."""

    centres: tuple[Point, ...] = tuple((x, y) for x, y, _ in PILLARS)
    clearance: float = CLEARANCE

    def blocked(self, point: Point) -> Point | None:
        """The obstacle ``point`` is too near, or None."""
        return next(
            (c for c in self.centres if math.hypot(point[0] - c[0], point[1] - c[1]) < self.clearance), None
        )

    def clear_line(self, start: Point, end: Point) -> bool:
        """Whether the robot can drive straight from ``start`` to ``end`` without touching an obstacle."""
        return all(_segment_distance(c, start, end) >= self.clearance for c in self.centres)


def plan_path(start: Point, goal: Point, obstacles: Obstacles | None = None) -> list[Point]:
    """Waypoints from ``start`` (excluded) to ``goal`` (included) around ``obstacles``.

    Raises :class:`PlanningError` with the reason when there is no path.
    """
    obstacles = obstacles or Obstacles()
    hit = obstacles.blocked(goal)
    if hit is not None:
        raise PlanningError(
            f"the goal ({goal[0]:g}, {goal[1]:g}) is inside an obstacle: a pillar stands at "
            f"({hit[0]:g}, {hit[1]:g}); pick a point at least {obstacles.clearance:.2f} m from it"
        )
    if obstacles.clear_line(start, goal):
        return [goal]
    xs = [start[0], goal[0], *(c[0] for c in obstacles.centres)]
    ys = [start[1], goal[1], *(c[1] for c in obstacles.centres)]
    grid = _Grid(min(xs) - MARGIN, min(ys) - MARGIN, max(xs) + MARGIN, max(ys) + MARGIN)
    if grid.width * grid.height > MAX_CELLS:
        raise PlanningError(
            f"the goal ({goal[0]:g}, {goal[1]:g}) is too far to plan for in one go; go there in shorter legs"
        )
    cells = _astar(grid, grid.cell(start), grid.cell(goal), obstacles)
    if cells is None:
        raise PlanningError(f"no path reaches ({goal[0]:g}, {goal[1]:g}): obstacles cut it off")
    points = [grid.centre(cell) for cell in cells[1:-1]] + [goal]
    return _shortcut(start, points, obstacles)


def path_length(start: Point, waypoints: list[Point]) -> float:
    """Metres along ``waypoints`` from ``start``."""
    total, here = 0.0, start
    for point in waypoints:
        total += math.hypot(point[0] - here[0], point[1] - here[1])
        here = point
    return total


@dataclass
class PathPilot:
    """Follows waypoints forward (never backing up), then turns to ``yaw`` if one was asked."""

    waypoints: list[Point]
    yaw: float | None
    speed: float
    turn_speed: float
    _leg: Autopilot | None = field(default=None, init=False)

    def command(self, world: DiffDriveWorld) -> tuple[float, float] | None:
        """The twist to apply now, or None once the last waypoint (and heading) is reached."""
        while self.waypoints:
            if self._leg is None:
                self._leg = self._next_leg(world)
            target = self.waypoints[0]
            last = len(self.waypoints) == 1
            near = math.hypot(target[0] - world.x, target[1] - world.y) < WAYPOINT_REACHED
            twist = None if (near and not last) else self._leg.command(world)
            if twist is not None:
                return twist
            self.waypoints.pop(0)
            self._leg = None
        return None

    def _next_leg(self, world: DiffDriveWorld) -> Autopilot:
        x, y = self.waypoints[0]
        if len(self.waypoints) > 1:
            yaw = math.atan2(self.waypoints[1][1] - y, self.waypoints[1][0] - x)
        else:
            yaw = self.yaw if self.yaw is not None else math.atan2(y - world.y, x - world.x)
        return Autopilot(x, y, wrap_angle(yaw), self.speed, self.turn_speed, forward_only=True)

    def remaining(self, world: DiffDriveWorld) -> float:
        """Metres left along the path."""
        return path_length((world.x, world.y), self.waypoints)


@dataclass(frozen=True)
class _Grid:
    left: float
    bottom: float
    right: float
    top: float

    @property
    def width(self) -> int:
        return math.ceil((self.right - self.left) / CELL) + 1

    @property
    def height(self) -> int:
        return math.ceil((self.top - self.bottom) / CELL) + 1

    def cell(self, point: Point) -> tuple[int, int]:
        return round((point[0] - self.left) / CELL), round((point[1] - self.bottom) / CELL)

    def centre(self, cell: tuple[int, int]) -> Point:
        return self.left + cell[0] * CELL, self.bottom + cell[1] * CELL


_STEPS = [(dx, dy) for dx in (-1, 0, 1) for dy in (-1, 0, 1) if dx or dy]


def _astar(
    grid: _Grid, start: tuple[int, int], goal: tuple[int, int], obstacles: Obstacles
) -> list[tuple[int, int]] | None:
    """8-connected A* on ``grid``; the start cell may be blocked (a robot brushing a pillar gets out)."""

    def h(cell: tuple[int, int]) -> float:
        return math.hypot(cell[0] - goal[0], cell[1] - goal[1])

    frontier: list[tuple[float, tuple[int, int]]] = [(h(start), start)]
    came_from: dict[tuple[int, int], tuple[int, int]] = {}
    cost = {start: 0.0}
    while frontier:
        _, current = heapq.heappop(frontier)
        if current == goal:
            path = [current]
            while current in came_from:
                current = came_from[current]
                path.append(current)
            return path[::-1]
        for dx, dy in _STEPS:
            nxt = (current[0] + dx, current[1] + dy)
            if not (0 <= nxt[0] < grid.width and 0 <= nxt[1] < grid.height):
                continue
            if nxt != goal and obstacles.blocked(grid.centre(nxt)) is not None:
                continue
            new_cost = cost[current] + math.hypot(dx, dy)
            if new_cost < cost.get(nxt, math.inf):
                cost[nxt] = new_cost
                came_from[nxt] = current
                heapq.heappush(frontier, (new_cost + h(nxt), nxt))
    return None


def _shortcut(start: Point, points: list[Point], obstacles: Obstacles) -> list[Point]:
    """Drop waypoints a straight line can skip: the grid's staircase becomes a few straight legs."""
    result: list[Point] = []
    here, index = start, 0
    while index < len(points):
        furthest = index
        for candidate in range(len(points) - 1, index, -1):
            if obstacles.clear_line(here, points[candidate]):
                furthest = candidate
                break
        result.append(points[furthest])
        here, index = points[furthest], furthest + 1
    return result


def _segment_distance(point: Point, start: Point, end: Point) -> float:
    """Distance from ``point`` to the segment ``start``-``end``."""
    sx, sy = end[0] - start[0], end[1] - start[1]
    length2 = sx * sx + sy * sy
    if length2 == 0:
        return math.hypot(point[0] - start[0], point[1] - start[1])
    t = max(0.0, min(1.0, ((point[0] - start[0]) * sx + (point[1] - start[1]) * sy) / length2))
    return math.hypot(point[0] - start[0] - t * sx, point[1] - start[1] - t * sy)
