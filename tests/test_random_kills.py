"""No command runs twice, and every run is reported, however often the kernel is killed with SIGKILL.

A stream of "toggle the X light" commands, one per lamp, is queued on ``rosaos up`` (offline
engine). The kernel is then killed with SIGKILL at random moments, restarted, and the commands are
posted again with their idempotency keys (as a client that lost its answers would), over and over.
The lamps live in the test process (:mod:`lamp_rack`), so they outlive every kernel and count
every ``toggle`` they receive. At the end:

- no lamp was toggled more than once: a launch recorded before the kill is never launched again;
- every command is accounted for: a lamp that was toggled has its process's end on the updates
  stream (ok, or crashed with the kernel), and a lamp that was not has a crashed process or a
  refusal saying why.

``ROSAOS_RANDOM_KILLS`` sets the number of kills (default 4; the issue asks for 20: run it so
before a release). Each kill costs a kernel start: 16-20 s on a two-core machine at load 15
(only the tapo driver is loaded, ``ROSAOS_DRIVERS=tapo``; all drivers: 23 s), so 20 kills take
6-7 minutes there, more than a CI job should spend on one test. ``ROSAOS_RANDOM_SEED`` replays a run.
"""

from __future__ import annotations

import os
import random
import signal
import time
from pathlib import Path

import httpx
import pytest

from .lamp_rack import LampRack
from .test_orphans_after_kernel_kill import start_kernel

ROOMS = ["kitchen", "hall", "porch", "garage", "attic", "office"]
KILLS = int(os.environ.get("ROSAOS_RANDOM_KILLS", "4"))
TOKEN = "lamp-rack-token"


def post_commands(api: httpx.Client) -> list[int]:
    """Queue one toggle per lamp (again: the keys make a re-post a no-op); return the event ids."""
    ids = []
    for room in ROOMS:
        answer = api.post(
            "/chat", json={"text": f"toggle the {room} light"}, headers={"Idempotency-Key": f"toggle-{room}"}
        )
        answer.raise_for_status()
        ids.append(answer.json()["id"])
    return ids


def settled(api: httpx.Client, event_ids: list[int]) -> bool:
    handled = all(api.get(f"/events/{event_id}").json()["handled"] for event_id in event_ids)
    return handled and not api.get("/processes").json()


def test_random_kernel_kills_run_no_command_twice_and_lose_no_run(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("ROSAOS_DRIVERS", "tapo")  # only the lamps' driver: each restart imports less
    rack = LampRack(tmp_path, [f"{room}_light" for room in ROOMS], TOKEN).start()
    try:
        config = tmp_path / "rosaos.toml"
        config.write_text(
            f'data_dir = "{tmp_path / "data"}"\n[kernel]\npool_size = 1\n'
            + "".join(
                f'[devices.{name}]\ndriver = "tapo"\nurl = "{url}"\ntoken = "{TOKEN}"\n'
                f'description = "Ceiling light in the {name.split("_")[0]}"\n'
                for name, url in rack.urls.items()
            )
        )
        chance = random.Random(int(os.environ.get("ROSAOS_RANDOM_SEED", time.time_ns())))
        kills = 0
        while True:
            kernel, url = start_kernel(config)
            token = (tmp_path / "data" / "token").read_text().strip()
            api = httpx.Client(base_url=url, headers={"Authorization": f"Bearer {token}"}, timeout=10)
            try:
                event_ids = post_commands(api)
                if kills == KILLS:
                    deadline = time.monotonic() + 120
                    while not (done := settled(api, event_ids)) and time.monotonic() < deadline:
                        time.sleep(0.2)
                    assert done, "the last kernel did not handle the whole stream within 120 s"
                    updates = api.get("/updates", params={"after": 0, "limit": 1000}).json()["updates"]
                    break
                # Kill somewhere in the stream of launches, once this kernel has run one (or has
                # nothing left to run): the banner comes before the devices and the pool are up
                # (issue 27), and a kill before any command ran would test nothing.
                ran = sum(rack.counts.values())
                deadline = time.monotonic() + 60
                while sum(rack.counts.values()) == ran and time.monotonic() < deadline:
                    if settled(api, event_ids):
                        break
                    time.sleep(0.05)
                time.sleep(chance.uniform(0.0, 1.0))
            finally:
                api.close()
                if kills == KILLS:
                    kernel.send_signal(signal.SIGINT)
                    kernel.wait(60)
                else:
                    kernel.send_signal(signal.SIGKILL)
                    kernel.wait()
            kills += 1
    finally:
        rack.close()

    toggles = dict(rack.counts)
    twice = {lamp: count for lamp, count in toggles.items() if count > 1}
    assert not twice, f"commands that ran more than once: {twice}"
    ended = [u for u in updates if u["kind"] == "process_ended"]
    for room in ROOMS:
        lamp = f"{room}_light"
        reports = [u for u in ended if f"{room} light" in u["data"]["task"].lower()]
        if toggles.get(lamp):
            assert reports, f"{lamp} was toggled, but no process end reports it"
        else:
            # A refusal (the lamp unreachable on a busy machine, say) is told as a notice and a reply.
            said_why = [
                u for u in updates if u["kind"] in ("error", "notice") and f"{lamp} is not" in u["text"]
            ]
            crashed = [u for u in reports if u["data"]["status"] == "crashed"]
            assert crashed or said_why, f"{lamp} was never toggled, and nothing says why: {reports}"
    assert sum(toggles.values()) >= len(ROOMS) // 2, f"too few commands ran to test anything: {toggles}"
