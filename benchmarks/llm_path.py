"""The LLM path (issue 22): model requests, bytes, tokens and time to the device, with a model in the loop.

Starts the real ``rosaos up`` (demo world, fresh data directory, loopback port) with every kernel
and process request sent to a scripted OpenAI-compatible server on loopback
(``benchmarks/llm_scripted_server.py``) and ``prefer_local = false``, so the "model" handles even
the commands the offline engine knows. Per latency profile it:

1. sends 8 earlier commands (no latency), so the kernel's history is that of a session in use;
2. sends "turn on the kitchen light" and waits until everything settled;
3. sends the paper's demo sentence (undock, search for a person, then turn the lamp green).

For 2 and 3 it reports the model requests (kernel, process), their bytes and estimated tokens
(bytes / 4), and the seconds from ``POST /chat`` to the first device change, read from that call's
receipt in the activity log (``started + duration``; nothing polls the device meanwhile). The
latency profiles (issue 22): "cloud" 0.4 s + 0.2 ms per prompt token + 10 ms per output token;
"local-8b" 0.5 ms per prompt token + 25 ms per output token. It measures, it does not assert.

    .venv/bin/python benchmarks/llm_path.py [--profiles cloud local-8b] [--port 19410] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx

sys.path.insert(0, str(Path(__file__).parent))
from llm_scripted_server import DEMO_SENTENCE, PROFILES, Logged, Script, serve

EARLIER = [
    "turn on the kitchen light",
    "turn on the living room lamp",
    "make the living room lamp blue",
    "play some jazz",
    "pause the music",
    "turn off the living room lamp",
    "turn on the living room lamp",
    "turn off the kitchen light",
]
"""The 8 commands before the measured one; the last leaves the kitchen light off."""
BANNER = "rosaOS is up at"
SETTLE = 240.0
"""Seconds a command may take before the run counts as stuck."""
CHANGES = {"turn_on", "turn_off", "set_color_name", "play", "pause", "undock", "search"}


def start(port: int, llm_port: int, home: Path) -> tuple[subprocess.Popen[str], str]:
    """``rosaos up`` on ``port`` with the scripted model; returns the process and its API token."""
    env = dict(
        os.environ,
        ROSAOS_DATA_DIR=str(home / "data"),
        ROSAOS_MODELS__KERNEL="openai-compatible",
        ROSAOS_MODELS__BASE_URL=f"http://127.0.0.1:{llm_port}/v1",
        ROSAOS_MODELS__MODEL_NAME="scripted",
        ROSAOS_MODELS__PREFER_LOCAL="false",
        COLUMNS="200",
    )
    env.pop("ROSAOS_CONFIG", None)
    command = [sys.executable, "-m", "rosaos.cli", "up", "--port", str(port)]
    up = subprocess.Popen(
        command, cwd=home, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    )
    assert up.stdout is not None
    deadline = time.monotonic() + 300
    for line in up.stdout:
        if BANNER in line:
            break
        if time.monotonic() > deadline:
            raise RuntimeError("rosaos up did not start in 300 s")
    else:
        raise RuntimeError("rosaos up exited before its banner")
    return up, (home / "data" / "token").read_text().strip()


def wait_healthy(api: httpx.Client) -> None:
    """Until every device is healthy (the simulators take a moment; longer on a loaded machine)."""
    deadline = time.monotonic() + 600
    while time.monotonic() < deadline:
        devices = api.get("/devices").json()
        if devices and all(d.get("status") == "healthy" for d in devices):
            return
        time.sleep(0.2)
    raise RuntimeError(f"devices not healthy: {[(d['name'], d.get('status')) for d in devices]}")


def settle(api: httpx.Client, script: Script, quiet: float = 0.5) -> None:
    """Until no process runs, no event is pending and the model has been quiet for ``quiet`` s."""
    deadline = time.monotonic() + SETTLE
    while time.monotonic() < deadline:
        running = [p for p in api.get("/processes").json() if p["state"] == "running"]
        pending = api.get("/health").json()["pending_events"]
        with script.lock:
            last = script.log[-1].at if script.log else 0.0
        if not running and pending == 0 and time.time() - last > quiet:
            return
        time.sleep(0.05)
    raise RuntimeError("the command did not settle in time")


def first_change(api: httpx.Client, since: float) -> float | None:
    """End time (epoch) of the first successful state-changing device call started after ``since``."""
    entries = api.get("/activity", params={"since": since}).json()["entries"]
    ends = [
        e["started"] + e["duration"]
        for e in entries
        if e["ok"] and any(e["tool"] == name or e["tool"].endswith(f"_{name}") for name in CHANGES)
    ]
    return min(ends) if ends else None


def summarize(log: list[Logged]) -> dict[str, Any]:
    return {
        "requests": len(log),
        "kernel_requests": sum(1 for r in log if r.role == "kernel"),
        "process_requests": sum(1 for r in log if r.role == "process"),
        "bytes": sum(r.bytes for r in log),
        "tokens": sum(r.prompt_tokens for r in log),
        "largest_request_bytes": max((r.bytes for r in log), default=0),
        "process_tools_offered": max((r.tools for r in log if r.role == "process"), default=0),
        "model_seconds": round(sum(r.seconds for r in log), 3),
        "per_request": [
            {
                "role": r.role,
                "bytes": r.bytes,
                "system_bytes": r.system_bytes,
                "tools": r.tools,
                "tool_bytes": r.tool_bytes,
                "prompt_tokens": r.prompt_tokens,
                "prefilled_tokens": r.prefilled_tokens,
                "output_tokens": r.output_tokens,
                "seconds": r.seconds,
            }
            for r in log
        ],
    }


def measure(api: httpx.Client, script: Script, sentence: str, profile: str) -> dict[str, Any]:
    wait_healthy(api)  # on a loaded machine a device may be briefly marked unhealthy: not what this measures
    script.reset(PROFILES[profile])
    posted = time.time()
    api.post("/chat", json={"text": sentence}).raise_for_status()
    settle(api, script)
    changed = first_change(api, posted - 0.01)
    result = summarize(script.log)
    result["seconds_to_device"] = None if changed is None else round(changed - posted, 3)
    return result


def run(port: int, profiles: list[str], dump: Path | None = None, light_only: bool = False) -> dict[str, Any]:
    server, script = serve()
    llm_port = server.server_address[1]
    results: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        up, token = start(port, int(llm_port), Path(tmp))
        try:
            headers = {"Authorization": f"Bearer {token}"}
            with httpx.Client(base_url=f"http://127.0.0.1:{port}", headers=headers, timeout=120) as api:
                wait_healthy(api)
                for profile in profiles:
                    script.reset(PROFILES["none"])
                    for sentence in EARLIER:
                        wait_healthy(api)
                        api.post("/chat", json={"text": sentence}).raise_for_status()
                        settle(api, script, quiet=0.2)
                    commands = {"light switch": "turn on the kitchen light"}
                    if not light_only:
                        commands["paper demo"] = DEMO_SENTENCE
                    results[profile] = {}
                    for name, sentence in commands.items():
                        if dump is not None:
                            (dump / profile / name.replace(" ", "-")).mkdir(parents=True, exist_ok=True)
                            script.dump = str(dump / profile / name.replace(" ", "-"))
                        results[profile][name] = measure(api, script, sentence, profile)
                        script.dump = None
                    # Back to the start: the robot docks again for the next profile's demo.
                    script.reset(PROFILES["none"])
        finally:
            up.send_signal(signal.SIGINT)
            try:
                up.wait(timeout=30)
            except subprocess.TimeoutExpired:
                up.kill()
            server.shutdown()
    return results


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--profiles", nargs="+", default=["cloud", "local-8b"], choices=sorted(PROFILES))
    parser.add_argument("--port", type=int, default=19410, help="port for rosaos up (default 19410)")
    parser.add_argument("--json", type=Path, help="also write the results here")
    parser.add_argument(
        "--dump", type=Path, help="write every measured request body here (PROFILE/COMMAND/NNN-role.json)"
    )
    parser.add_argument("--light-only", action="store_true", help="skip the paper's demo")
    args = parser.parse_args()
    results = {}
    for profile in args.profiles:  # a fresh rosaos up per profile: same history, same robot pose
        results.update(run(args.port, [profile], args.dump, args.light_only))
    load = os.getloadavg()[0]
    print(f"load average (1 min) at the end: {load:.1f} on {os.cpu_count()} cores")
    header = "| profile | command | requests (kernel + process) | bytes | est. tokens | tools offered to the process | s to device |"
    print(header)
    print("|---|---|---|---|---|---|---|")
    for profile, commands in results.items():
        for command, r in commands.items():
            print(
                f"| {profile} | {command} | {r['requests']} ({r['kernel_requests']} + {r['process_requests']}) "
                f"| {r['bytes']:,} | {r['tokens']:,} | {r['process_tools_offered']} | {r['seconds_to_device']} |"
            )
    print("\nWhere the model's seconds go (per request: prompt bytes = system + tools + the rest):")
    for profile, commands in results.items():
        for command, r in commands.items():
            for q in r["per_request"]:
                rest = q["bytes"] - q["system_bytes"] - q["tool_bytes"]
                print(
                    f"  {profile:>15} {command:<12} {q['role']:<7} {q['bytes']:>6} B = {q['system_bytes']:>5} + "
                    f"{q['tool_bytes']:>5} ({q['tools']} tools) + {rest:>5}; prefilled {q['prefilled_tokens']:>5} tok, "
                    f"out {q['output_tokens']:>3} tok: {q['seconds']:.2f} s"
                )
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"load": load, "results": results}, indent=2))


if __name__ == "__main__":
    main()
