"""Robots driving while the lamps are switched: the robot half of ``scale.py --robots K``.

K ROS robot simulators (TurtleBot 4 and PuppyPi in turn, ``robot_0`` … "Robot 0" …) join the
lamps in the same ``rosaos.toml``. During the lamp burst each robot is told "move robot k forward
one meter" again and again, one leg after another, until the burst has settled (at least one
leg each). A leg's outcome is read from the robot itself, not from a reply: its ``get_state``
over MCP before the command and after its process ended; the leg is ``ok`` when the robot
travelled one metre (within :data:`TOLERANCE`) and stands still.
"""

from __future__ import annotations

import asyncio
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx
from footprint import served

from rosaos.devices.client import DeviceClient

LEG_METRES = 1.0
TOLERANCE = 0.1
"""Metres a leg may fall short of or overshoot its metre and still count as done."""
LEG_LIMIT = 120.0
"""Seconds a leg may take before it counts as not done."""


def robot_world(count: int) -> list[str]:
    """``rosaos.toml`` lines for ``count`` robot simulators."""
    lines = []
    for k in range(count):
        kind = ("TurtleBot 4 wheeled robot", "turtlebot4") if k % 2 == 0 else ("PuppyPi robot dog", "puppypi")
        lines += [
            f"[devices.robot_{k}]",
            'driver = "ros"',
            f'description = "Robot {k}, a {kind[0]}"',
            f'profile = "{kind[1]}"',
            *(["sim = { docked = false }"] if kind[1] == "turtlebot4" else []),
            "",
        ]
    return lines


@dataclass
class Leg:
    robot: str
    event: int
    start: dict[str, Any]
    ended: asyncio.Event = field(default_factory=asyncio.Event)
    status: str | None = None


class RobotDrivers:
    """Drives every robot leg after leg until :meth:`stop`; the lamp burst's update loop calls
    :meth:`launched` and :meth:`ended` for the updates it reads."""

    def __init__(self, api: httpx.AsyncClient, data_dir: Path, count: int) -> None:
        self.api = api
        self.count = count
        self.token = (data_dir / "token").read_text().strip()
        self.urls = {name: row["url"] for name, row in served(data_dir).items() if name.startswith("robot_")}
        self.legs: dict[int, Leg] = {}  # event id → leg
        self.processes: dict[int, Leg] = {}  # process id → leg
        self.results: list[dict[str, Any]] = []
        self._early: dict[int, int] = {}  # event id → process id, launched before the leg was known
        self._stopping = asyncio.Event()
        self._tasks: list[asyncio.Task[None]] = []

    def start(self) -> None:
        self._tasks = [asyncio.create_task(self._drive(f"robot_{k}")) for k in range(self.count)]

    def launched(self, event: int | None, process: int) -> None:
        if event is None:
            return
        if event in self.legs:
            self.processes[process] = self.legs[event]
        else:  # read before the leg's POST answer was: kept until the leg is known
            self._early[event] = process

    def ended(self, process: int, status: str, error: str | None = None) -> None:
        leg = self.processes.get(process)
        if leg is not None:
            leg.status = status if error is None else f"{status}: {error}"
            leg.ended.set()

    async def stop(self) -> dict[str, Any]:
        """Let each robot finish its current leg, then sum up."""
        self._stopping.set()
        await asyncio.gather(*self._tasks)
        legs = len(self.results)
        done = [r for r in self.results if r["done"]]
        return {
            "robots": self.count,
            "legs": legs,
            "legs_done": len(done),
            "legs_per_robot": {
                f"robot_{k}": sum(1 for r in self.results if r["robot"] == f"robot_{k}")
                for k in range(self.count)
            },
            "leg_s_p50": round(sorted(r["seconds"] for r in done)[len(done) // 2], 2) if done else None,
            "not_done": [r for r in self.results if not r["done"]][:5],
        }

    async def _state(self, robot: str) -> dict[str, Any]:
        return await DeviceClient(self.urls[robot], self.token, 30, robot).get_state()

    async def _drive(self, robot: str) -> None:
        number = robot.split("_")[1]
        while True:
            start = await self._state(robot)
            began = time.perf_counter()
            reply = await self.api.post("/chat", json={"text": f"move robot {number} forward one meter"})
            reply.raise_for_status()
            leg = Leg(robot, int(reply.json()["id"]), start)
            self.legs[leg.event] = leg
            if leg.event in self._early:
                self.processes[self._early.pop(leg.event)] = leg
            try:
                await asyncio.wait_for(leg.ended.wait(), LEG_LIMIT)
            except TimeoutError:
                leg.status = "no end seen"
            end = await self._state(robot)
            travelled = math.hypot(end["x"] - start["x"], end["y"] - start["y"])
            still = abs(end.get("linear", 0.0)) < 0.01
            self.results.append(
                {
                    "robot": robot,
                    "status": leg.status,
                    "travelled_m": round(travelled, 3),
                    "still": still,
                    "done": abs(travelled - LEG_METRES) <= TOLERANCE and still,
                    "seconds": round(time.perf_counter() - began, 2),
                }
            )
            if self._stopping.is_set():
                return
