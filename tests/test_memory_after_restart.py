"""Memory outlives the kernel: places in their frame, and aliases, across a SIGKILL and a restart.

A real ``rosaos up`` (offline engine) runs two simulated robots: a TurtleBot 4 with Nav2 on a map,
and a PuppyPi dog with odometry only. Before the kill it is told "remember this spot as the
kitchen" (the TurtleBot stands at (3.5, 0)), "dog, remember this spot as the doghouse" and "call
the dog Rex". It is killed with SIGKILL, and started again with the TurtleBot at the origin (a
simulator starts where its sim table says: the robot was carried off) and the dog's odometry
starting from another origin (it booted elsewhere). Then:

- "go to the kitchen": the TurtleBot drives around the red pillar at (2, 0) and arrives within 0.2 m;
- "Rex, go to the doghouse": refused with the reason, and the dog does not move;
- "Rex, walk forward one metre": the dog walks.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from .cli_process import ROSAOS, line_matching

ROBOTS = """
[devices.turtlebot]
driver = "ros"
description = "TurtleBot 4 wheeled mobile robot"
sim = {{ profile = "turtlebot4", x = {x}, y = 0.0, docked = false }}

[devices.dog]
driver = "ros"
description = "PuppyPi quadruped robot dog"
sim = {{ profile = "puppypi", odom_origin = {{ x = {origin}, y = 0.0 }}, x = {origin}, y = 0.0 }}
"""


def until(check: Callable[[], Any], timeout: float = 90.0, what: str = "condition") -> Any:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if value := check():
            return value
        time.sleep(0.2)
    raise AssertionError(f"{what} did not happen within {timeout} s")


class RosaosUp:
    """``rosaos up`` in a subprocess with a config the test rewrites between runs."""

    def __init__(self, tmp_path: Path) -> None:
        self.config = tmp_path / "rosaos.toml"
        self.data = tmp_path / "data"
        self.process: subprocess.Popen[str] | None = None

    def start(self, turtlebot_x: float, dog_origin: float) -> httpx.Client:
        self.config.write_text(
            f'data_dir = "{self.data}"\n[kernel]\npool_size = 1\n'
            + ROBOTS.format(x=turtlebot_x, origin=dog_origin)
        )
        self.process = subprocess.Popen(
            [str(ROSAOS), "up", "--config", str(self.config), "--port", "0"],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env={**os.environ, "COLUMNS": "200"},
        )
        url = line_matching(self.process, r"rosaOS is up at (http://\S+?)/?$").group(1)
        token = (self.data / "token").read_text().strip()
        return httpx.Client(base_url=url, headers={"Authorization": f"Bearer {token}"}, timeout=10)

    def kill_9(self) -> None:
        assert self.process is not None
        self.process.send_signal(signal.SIGKILL)
        self.process.wait()

    def stop(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(60)
            except subprocess.TimeoutExpired:
                self.process.kill()


@pytest.fixture
def rosaos(tmp_path: Path) -> Iterator[RosaosUp]:
    under_test = RosaosUp(tmp_path)
    try:
        yield under_test
    finally:
        under_test.stop()


def say(api: httpx.Client, text: str, replies: int = 1) -> list[str]:
    """Type ``text``; the kernel's first ``replies`` replies to it (a process's callback is the second)."""
    event_id = api.post("/chat", json={"text": text}).raise_for_status().json()["id"]

    def answered() -> list[str]:
        said = [u["text"] for u in updates(api) if u["kind"] == "kernel_reply" and u["event_id"] == event_id]
        callbacks = [
            u["text"] for u in updates(api) if u["kind"] == "kernel_reply" and u["event_id"] > event_id
        ]
        found = said + callbacks
        return found[:replies] if len(found) >= replies else []

    return list(until(answered, what=f"{replies} replies to {text!r}"))


def updates(api: httpx.Client) -> list[dict[str, Any]]:
    found: list[dict[str, Any]] = api.get("/updates", params={"after": 0, "limit": 1000}).json()["updates"]
    return found


def state(api: httpx.Client, device: str) -> dict[str, Any]:
    devices = api.get("/devices").raise_for_status().json()
    found: dict[str, Any] = next(d for d in devices if d["name"] == device)["state"] or {}
    return found


def test_places_and_aliases_survive_a_kill_and_a_changed_frame_is_refused(rosaos: RosaosUp) -> None:
    with rosaos.start(turtlebot_x=3.5, dog_origin=0.0) as api:
        until(lambda: state(api, "turtlebot").get("x") is not None, what="the turtlebot's state")
        [saved] = say(api, "remember this spot as the kitchen")
        assert saved.startswith("Saved the kitchen (x 3.50, y 0.00 on the turtlebot's map frame)")
        [doghouse] = say(api, "dog, remember this spot as the doghouse")
        assert "odom frame" in doghouse
        assert say(api, "call the dog Rex") == ["OK, Rex is the dog."]
        assert "the kitchen (turtlebot)" in say(api, "which places do you know?")[0]
    rosaos.kill_9()

    with rosaos.start(turtlebot_x=0.0, dog_origin=1.0) as api:
        until(lambda: state(api, "turtlebot").get("x") is not None, what="the turtlebot's state")
        assert state(api, "turtlebot")["x"] == pytest.approx(0.0, abs=0.05)
        going = api.post("/chat", json={"text": "go to the kitchen"}).raise_for_status().json()["id"]
        widest = 0.0
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:  # watch the trip: it must swing around the pillar at (2, 0)
            here = state(api, "turtlebot")
            widest = max(widest, abs(here.get("y") or 0.0))
            done = [u["text"] for u in updates(api) if u["kind"] == "kernel_reply" and u["event_id"] > going]
            if any("I'm at the kitchen" in text or "Sorry" in text for text in done):
                break
            time.sleep(0.3)
        assert any("I'm at the kitchen" in text for text in done), done
        arrived = state(api, "turtlebot")
        assert math.hypot(arrived["x"] - 3.5, arrived["y"]) < 0.2
        assert widest > 0.3, "the robot drove straight through the pillar"

        dog_before = state(api, "dog")
        [refused] = say(api, "Rex, go to the doghouse")
        assert "I won't drive there" in refused and "odometry" in refused
        time.sleep(1.0)
        assert state(api, "dog")["x"] == pytest.approx(dog_before["x"], abs=0.01)

        say(api, "Rex, walk forward one metre")
        until(lambda: state(api, "dog")["x"] - dog_before["x"] > 0.9, what="the dog walking a metre")
