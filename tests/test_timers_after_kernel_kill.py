"""Timers outlive the kernel: SIGKILL ``rosaos up`` with timers set, start it again.

A real ``rosaos up`` (offline engine, a simulated kitchen light) is told "turn off the kitchen
light in 3 seconds" and another timer that is then cancelled, and is killed with SIGKILL before
either is due. After the restart:

- the first timer fires exactly once: one ``timer_fired`` event, its process turns the light off;
- the cancelled one never fires: the light keeps its brightness;
- a timer that fell due during a long outage fires once at start-up, and the kernel says how late.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from .cli_process import ROSAOS, line_matching


def until(check: Callable[[], Any], timeout: float = 60.0, what: str = "condition") -> Any:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if value := check():
            return value
        time.sleep(0.1)
    raise AssertionError(f"{what} did not happen within {timeout} s")


class KernelUnderTest:
    """``rosaos up`` in a subprocess, on a port of its own choosing, with its data directory."""

    def __init__(self, tmp_path: Path) -> None:
        self.config = tmp_path / "rosaos.toml"
        self.config.write_text(
            f'data_dir = "{tmp_path / "data"}"\n[kernel]\npool_size = 1\n'
            '[devices.kitchen_light]\ndriver = "tapo"\ndescription = "Ceiling light in the kitchen"\n'
            "sim = { on = true, brightness = 60 }\n"
        )
        self.data = tmp_path / "data"
        self.process: subprocess.Popen[str] | None = None
        self.url = ""

    def start(self) -> httpx.Client:
        self.process = subprocess.Popen(
            [str(ROSAOS), "up", "--config", str(self.config), "--port", "0"],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env={**os.environ, "COLUMNS": "200"},
        )
        self.url = line_matching(self.process, r"rosaOS is up at (http://\S+?)/?$").group(1)
        token = (self.data / "token").read_text().strip()
        return httpx.Client(base_url=self.url, headers={"Authorization": f"Bearer {token}"}, timeout=10)

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
def kernel(tmp_path: Path) -> Iterator[KernelUnderTest]:
    under_test = KernelUnderTest(tmp_path)
    try:
        yield under_test
    finally:
        under_test.stop()


def say(api: httpx.Client, text: str) -> str:
    """Type ``text`` and return the kernel's reply to it."""
    event_id = api.post("/chat", json={"text": text}).raise_for_status().json()["id"]
    return str(until(lambda: next(iter(replies(api, event_id)), None), what=f"a reply to {text!r}"))


def replies(api: httpx.Client, event_id: int) -> list[str]:
    return [u["text"] for u in all_updates(api) if u["kind"] == "kernel_reply" and u["event_id"] == event_id]


def all_updates(api: httpx.Client) -> list[dict[str, Any]]:
    updates: list[dict[str, Any]] = api.get("/updates", params={"after": 0, "limit": 1000}).json()["updates"]
    return updates


def timer_events(api: httpx.Client) -> list[dict[str, Any]]:
    return [u for u in all_updates(api) if u["kind"] == "event" and u["data"]["kind"] == "timer_fired"]


def timers(api: httpx.Client) -> dict[int, str]:
    listed = api.get("/timers", params={"all": "true"}).raise_for_status().json()["timers"]
    return {timer["id"]: timer["state"] for timer in listed}


def light(api: httpx.Client) -> dict[str, Any]:
    devices = api.get("/devices").raise_for_status().json()
    state: dict[str, Any] = next(d for d in devices if d["name"] == "kitchen_light")["state"] or {}
    return state


def test_a_timer_survives_a_kill_9_and_fires_once_and_a_cancelled_one_never(kernel: KernelUnderTest) -> None:
    with kernel.start() as api:
        assert say(api, "turn off the kitchen light in 3 seconds").startswith("Timer 1 set:")
        assert say(api, "set the kitchen light to 10 percent in 2 seconds").startswith("Timer 2 set:")
        assert "Cancelled timer 2" in say(api, "cancel that timer")
        assert timers(api) == {1: "pending", 2: "cancelled"}
    kernel.kill_9()

    with kernel.start() as api:
        until(lambda: timers(api)[1] == "fired", what="timer 1 firing")
        until(lambda: light(api).get("on") is False, what="the light turning off")
        time.sleep(1.0)  # room for a second firing, if there were one
        [fired] = timer_events(api)
        assert fired["data"]["payload"]["timer_id"] == 1
        assert timers(api) == {1: "fired", 2: "cancelled"}
        assert light(api)["brightness"] == 60, "the cancelled timer ran"


def test_a_timer_due_during_a_long_outage_fires_once_on_restart_and_says_it_is_late(
    kernel: KernelUnderTest,
) -> None:
    with kernel.start() as api:
        assert say(api, "in 2 seconds, turn off the kitchen light").startswith("Timer 1 set:")
    kernel.kill_9()
    time.sleep(8)  # the outage: the timer falls due while no kernel runs

    with kernel.start() as api:
        [fired] = until(lambda: timer_events(api), what="the late timer firing")
        assert fired["data"]["payload"]["late_seconds"] >= 6
        reply = until(lambda: next(iter(replies(api, fired["event_id"])), None), what="the timer's reply")
        assert re.match(
            r"Timer 1 \(\d+ (seconds|minutes?) late: the kernel was not running when it was due\): ", reply
        )
        until(lambda: light(api).get("on") is False, what="the light turning off")
        assert len(timer_events(api)) == 1
