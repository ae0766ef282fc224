"""Scale: N simulated lamps in one `rosaos up`, and a burst of N commands at once, quiet or busy.

For each N it writes a `rosaos.toml` with N Tapo simulators (`lamp_0` … "Lamp 0" …), starts the
real command in a fresh data directory on a free port, and measures:

- start-up: seconds to the banner, and to every device `healthy` (from `run/devices.json`), and
  the CPU seconds the tree used until the banner (what start-up costs, whatever the load);
- idle: PSS of the whole process tree, and its CPU over `--idle` seconds (% of one core);
- a burst: N concurrent `POST /chat` "turn on lamp k" (offline engine). Each command is timed
  from its POST to its process ending `ok` (the update's own timestamp); the burst is settled
  when every command has ended. It counts refusals (a `launch refused` notice or a process that
  did not end ok), the device notices published during the burst, and host restarts (the run
  file's restart counts and pids). Afterwards every lamp's state is read through `GET /devices`.

`--robots K` adds K ROS robot simulators (:mod:`scale_robots`) that drive one metre after another
while the lamps are switched; each leg's outcome is read from the robot's own state. `--py-spy
PATH` records the kernel's stacks during the burst (raw collapsed stacks beside the JSON), to see
where its CPU per command goes.

`--busy K` runs K CPU-bound processes (a busy loop each, stopping by themselves after
`--busy-seconds`) beside it for the whole run: the "busy" figures of issue 27. It measures, it
does not assert. Linux only (/proc).

    .venv/bin/python benchmarks/scale.py --n 10 100 300 [--busy 2] [--idle 20] [--robots 5]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import platform
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any

import httpx
from footprint import BANNER, children, cpu_seconds, free_port, host_instances, memory_kib, role, served
from scale_robots import LEG_LIMIT, RobotDrivers, robot_world

START_LIMIT = 300.0
BUSY_LOOP = (
    "import sys, time\nend = time.monotonic() + float(sys.argv[1])\nwhile time.monotonic() < end:\n    pass\n"
)


def world(n: int, data_dir: Path, robots: int = 0) -> str:
    lines = [f'data_dir = "{data_dir}"', "[kernel]", "pool_size = 2", "", *robot_world(robots)]
    for k in range(n):
        lines += [
            f"[devices.lamp_{k}]",
            'driver = "tapo"',
            f'description = "Lamp {k}"',
            "sim = { on = false }",
            "",
        ]
    return "\n".join(lines)


def start_busy(count: int, seconds: float) -> list[subprocess.Popen[bytes]]:
    """``count`` busy loops that end by themselves after ``seconds`` (killed at the end anyway)."""
    return [subprocess.Popen([sys.executable, "-c", BUSY_LOOP, str(seconds)]) for _ in range(count)]


def tree(pid: int) -> list[int]:
    return [pid, *children(pid)]


def cpu_by_role(pid: int, data_dir: Path) -> dict[str, float]:
    """CPU seconds so far per role of the tree (kernel, fork server, device host, workers).

    Reaped children count with their parent (a forked worker that ended, with the fork server):
    a difference of two of these says where a burst's CPU went."""
    hosts = {host: "shared" if "," in names else names for host, names in host_instances(data_dir).items()}
    found: dict[str, float] = {}
    for member in tree(pid):
        try:
            name = role(member, hosts, pid)
        except OSError:
            continue
        name = "workers" if name.startswith("worker") else name
        found[name] = found.get(name, 0.0) + cpu_seconds([member])
    return found


def cpu_spent(before: dict[str, float], after: dict[str, float]) -> dict[str, float]:
    return {name: round(after[name] - before.get(name, 0.0), 2) for name in sorted(after)}


def pss_mib(pid: int) -> float:
    total = 0
    for member in tree(pid):
        try:
            total += memory_kib(member).get("pss", 0)
        except OSError:
            continue
    return total / 1024


def wait_healthy(data_dir: Path, n: int, started: float) -> float | None:
    while time.perf_counter() - started < START_LIMIT:
        devices = served(data_dir)
        if len(devices) >= n and all(row.get("status") == "healthy" for row in devices.values()):
            return time.perf_counter() - started
        time.sleep(0.05)
    return None


def restarts(data_dir: Path) -> tuple[int, set[int]]:
    devices = served(data_dir)
    return sum(int(row.get("restarts") or 0) for row in devices.values()), {
        int(row["pid"]) for row in devices.values() if row.get("pid")
    }


async def burst(url: str, token: str, n: int, limit: float, data_dir: Path, robots: int) -> dict[str, Any]:
    """N concurrent "turn on lamp k"; follow the updates until every command ended or ``limit``.

    With ``robots``, those robots drive leg after leg meanwhile (:mod:`scale_robots`)."""
    headers = {"Authorization": f"Bearer {token}"}
    limits = httpx.Limits(max_connections=n + robots + 10)
    async with httpx.AsyncClient(base_url=url, headers=headers, timeout=60, limits=limits) as api:
        after = int((await api.get("/updates", params={"limit": 1})).json()["last_id"])
        sent: dict[int, float] = {}  # event id → POST time (epoch)
        post_errors: list[str] = []

        async def post(k: int) -> None:
            at, key = time.time(), str(uuid.uuid4())
            for attempt in range(5):  # the idempotency key makes a retry the same event
                try:
                    reply = await api.post(
                        "/chat", json={"text": f"turn on lamp {k}"}, headers={"Idempotency-Key": key}
                    )
                    reply.raise_for_status()
                    sent[reply.json()["id"]] = at
                    return
                except httpx.TransportError as error:  # a kept-alive socket the loaded server closed
                    post_errors.append(f"lamp {k}, attempt {attempt + 1}: {error!r}")
                    await asyncio.sleep(0.5)

        drivers = RobotDrivers(api, data_dir, robots) if robots else None
        if drivers is not None:
            drivers.start()
            await asyncio.sleep(2.0)  # the robots are moving when the lamp burst comes
        started = time.perf_counter()
        await asyncio.gather(*(post(k) for k in range(n)))
        launched: dict[int, int] = {}  # process id → event id
        ended: dict[int, tuple[str, float]] = {}  # event id → (status, latency)
        refused: list[str] = []
        notices: list[str] = []
        failures: list[str] = []  # why a process did not end ok
        replies: dict[int, str] = {}  # event id → the kernel's reply
        settled: float | None = None
        robots_done: asyncio.Task[dict[str, Any]] | None = None
        while time.perf_counter() - started < limit + (LEG_LIMIT if robots_done else 0):
            if settled is None and len(ended) + len(refused) >= len(sent):
                settled = time.perf_counter() - started
                if drivers is None:
                    break
                robots_done = asyncio.create_task(drivers.stop())
            if robots_done is not None and robots_done.done():
                break
            try:
                page = (await api.get("/updates", params={"after": after, "limit": 1000})).json()["updates"]
            except httpx.TransportError as error:  # a kept-alive connection the server closed: ask again
                print(f"GET /updates: {error!r}; asking again", flush=True)
                await asyncio.sleep(0.2)
                continue
            for update in page:
                after = update["id"]
                kind, data, event = update["kind"], update["data"], update.get("event_id")
                if drivers is not None and kind == "process_launched":
                    drivers.launched(event, int(data["process_id"]))
                elif drivers is not None and kind == "process_ended":
                    drivers.ended(int(data.get("process_id", -1)), str(data.get("status")), data.get("error"))
                if kind == "process_launched" and event in sent:
                    launched[int(data["process_id"])] = event
                elif kind == "process_ended" and int(data.get("process_id", -1)) in launched:
                    source = launched[int(data["process_id"])]
                    at = datetime.fromisoformat(update["time"]).timestamp()
                    ended[source] = (str(data.get("status")), at - sent[source])
                    if data.get("status") != "ok":
                        failures.append(f"{data.get('status')}: {data.get('error') or update['text']}")
                elif kind == "kernel_reply" and event in sent:
                    replies[event] = update["text"]
                elif kind == "notice" and update["text"].startswith("launch refused"):
                    refused.append(update["text"])
                elif kind == "notice":
                    notices.append(update["text"])
            if not page:
                await asyncio.sleep(0.1)
        if settled is None:
            settled = time.perf_counter() - started
        robot_report = None
        if drivers is not None:
            robot_report = await (robots_done or asyncio.create_task(drivers.stop()))
        latencies = sorted(latency for status, latency in ended.values() if status == "ok")
        print(f"burst ended after {settled:.1f} s: {len(latencies)} ok; reading the lamps…", flush=True)
        try:
            views = (await api.get("/devices", timeout=180)).json()
        except httpx.HTTPError as error:
            print(f"GET /devices failed: {error!r}", flush=True)
            views = []
    states = [
        (view.get("state") or {}).get("on") for view in views if view.get("name", "").startswith("lamp_")
    ]
    return {
        "commands": n,
        "post_errors": post_errors[:5],
        "robots": robot_report,
        "ok": len(latencies),
        "not_ok": sum(1 for status, _ in ended.values() if status != "ok"),
        "refused": len(refused),
        "unfinished": len(sent) - len(ended) - len(refused),
        "settled_s": round(settled, 2),
        "p50_s": round(statistics.median(latencies), 2) if latencies else None,
        "p95_s": round(latencies[max(0, int(0.95 * len(latencies)) - 1)], 2) if latencies else None,
        "notices": len(notices),
        "notice_texts": notices[:10],
        "refusal_texts": refused[:3],
        "failure_texts": failures[:5],
        "unfinished_replies": [replies.get(event, "") for event in sent if event not in ended][:5],
        "lamps_on": states.count(True),
        "lamps_off": states.count(False),
        "lamps_unread": states.count(None),  # GET /devices could not read them in time
    }


@dataclass(frozen=True)
class Options:
    busy: int
    busy_seconds: float
    idle: float
    burst_limit: float
    robots: int
    py_spy: Path | None
    """py-spy's executable: record the kernel's stacks during the burst (a file beside the JSON)."""
    results: Path


def one_run(n: int, options: Options) -> dict[str, Any]:
    loops = start_busy(options.busy, options.busy_seconds)
    try:
        with tempfile.TemporaryDirectory() as home:
            data_dir = Path(home) / "data"
            config = Path(home) / "rosaos.toml"
            config.write_text(world(n, data_dir, options.robots))
            env = dict(os.environ, ROSAOS_DATA_DIR=str(data_dir), COLUMNS="200")
            env.pop("ROSAOS_CONFIG", None)
            port = free_port()
            command = [sys.executable, "-m", "rosaos.cli", "up", "--config", str(config), "--port", str(port)]
            started = time.perf_counter()
            up = subprocess.Popen(
                command, cwd=home, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
            )
            try:
                return measure(up, n, data_dir, started, port, options)
            finally:
                up.send_signal(signal.SIGINT)
                try:
                    up.wait(60)
                except subprocess.TimeoutExpired:
                    up.kill()
                    up.wait()
    finally:
        for loop in loops:
            loop.kill()
            loop.wait()


def measure(
    up: subprocess.Popen[str], n: int, data_dir: Path, started: float, port: int, options: Options
) -> dict[str, Any]:
    assert up.stdout is not None
    lines: list[str] = []
    for line in up.stdout:
        lines.append(line.rstrip())
        if BANNER in line:
            break
    else:
        raise RuntimeError("rosaos up exited before its banner:\n" + "\n".join(lines[-20:]))
    banner = time.perf_counter() - started
    banner_cpu = cpu_seconds(tree(up.pid))
    banner_roles = cpu_by_role(up.pid, data_dir)
    # Drain its output from now on, so a full pipe never stalls it.
    drain = subprocess.Popen(["cat"], stdin=up.stdout, stdout=subprocess.DEVNULL)
    healthy = wait_healthy(data_dir, n + options.robots, started)
    time.sleep(10.0)  # let start-up work end before the idle window
    healthy_roles = cpu_by_role(up.pid, data_dir)
    cpu_before, at = cpu_seconds(tree(up.pid)), time.perf_counter()
    idle_before = cpu_by_role(up.pid, data_dir)
    time.sleep(options.idle)
    idle_cpu = (cpu_seconds(tree(up.pid)) - cpu_before) / (time.perf_counter() - at)
    idle_roles = cpu_spent(idle_before, cpu_by_role(up.pid, data_dir))
    pss = pss_mib(up.pid)
    run: dict[str, Any] = {
        "n": n,
        "banner_s": round(banner, 2),
        "banner_cpu_s": round(banner_cpu, 2),
        "banner_cpu_s_by_role": {name: round(value, 2) for name, value in sorted(banner_roles.items())},
        "all_healthy_s": None if healthy is None else round(healthy, 2),
        "start_cpu_s_by_role": {name: round(value, 2) for name, value in sorted(healthy_roles.items())},
        "idle_cpu_pct_of_one_core": round(100 * idle_cpu, 2),
        "idle_cpu_s_by_role": idle_roles,
        "idle_pss_mib": round(pss, 1),
    }
    print(json.dumps(run), flush=True)  # kept if the burst fails
    restarts_before, pids_before = restarts(data_dir)
    token = (data_dir / "token").read_text().strip()
    burst_before = cpu_by_role(up.pid, data_dir)
    spy = None
    if options.py_spy is not None:
        profile = options.results.with_name(f"{options.results.stem}-kernel-n{n}.txt")
        record = [str(options.py_spy), "record", "--pid", str(up.pid), "--format", "raw", "--rate", "100"]
        spy = subprocess.Popen([*record, "--nonblocking", "-o", str(profile)], stdout=subprocess.DEVNULL)
    try:
        url = f"http://127.0.0.1:{port}"
        result = asyncio.run(burst(url, token, n, options.burst_limit, data_dir, options.robots))
    finally:
        if spy is not None:
            spy.send_signal(signal.SIGINT)
            spy.wait(60)
    result["cpu_s_by_role"] = cpu_spent(burst_before, cpu_by_role(up.pid, data_dir))
    kernel_cpu = result["cpu_s_by_role"].get("kernel (rosaos up)", 0.0)
    result["kernel_cpu_ms_per_command"] = round(1000 * kernel_cpu / max(1, n), 1)
    restarts_after, pids_after = restarts(data_dir)
    drain.kill()
    run.update(
        burst=result,
        host_restarts=restarts_after - restarts_before,
        host_pids_changed=pids_before != pids_after,
    )
    return run


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--n", type=int, nargs="+", default=[10, 100], help="device counts (default 10 100)")
    parser.add_argument("--busy", type=int, default=0, help="CPU-bound busy loops beside it (default 0)")
    parser.add_argument("--busy-seconds", type=float, default=300.0, help="each busy loop stops after this")
    parser.add_argument("--idle", type=float, default=20.0, help="seconds of the idle CPU window")
    parser.add_argument("--burst-limit", type=float, default=180.0, help="seconds a burst may take")
    parser.add_argument("--robots", type=int, default=0, help="ROS robot simulators driving during the burst")
    parser.add_argument("--py-spy", type=Path, help="py-spy executable: record the kernel during the burst")
    parser.add_argument("--json", type=Path, default=Path("benchmarks/results/scale.json"))
    args = parser.parse_args()
    options = Options(
        args.busy, args.busy_seconds, args.idle, args.burst_limit, args.robots, args.py_spy, args.json
    )
    load_before = os.getloadavg()
    runs = []
    for n in args.n:
        print(f"N={n}, robots: {args.robots}, busy loops: {args.busy} …", flush=True)
        run = one_run(n, options)
        run["busy_loops"] = args.busy
        run["robots"] = args.robots
        run["load_after"] = os.getloadavg()
        runs.append(run)
        print(json.dumps(run, indent=1), flush=True)
    report = {
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(), "load_before": load_before},
        "runs": runs,
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=2))
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
